// The tick as a value (Drake style): a checked position and the law's state in, the command
// and the record's control fields out; no clock, no device, no ring. ServoLoop::run calls it
// on what the device read (after SampleCheck, loop/sample_check.h), `hapticd replay` on what a
// tick log recorded, so a log's forces come back bit for bit by construction
// (docs/architecture.md).
#pragma once

#include <cstdint>

#include "control/controller.h"
#include "control/passivity_observer.h"
#include "loop/sample_check.h"
#include "telemetry/tick_record.h"

namespace hapticd::loop {

struct TickInput {
  double position = 0.0;      // where the device is (held over a tick without a new sample)
  bool fresh = true;          // a new measurement this tick, not a held or stale one
  std::uint32_t periods = 1;  // sample periods since the previous tick (more after a skip)
  double client_force = 0.0;  // a client's commanded force this tick (N; loop/client_force.h)

  // RT-safe. What the loop's checks made of a read.
  static TickInput checked(const Sensed& s, std::uint32_t periods, double client) noexcept {
    return {s.position, s.fresh, periods, client};
  }
  // RT-safe. What a log recorded of a tick the loop stepped (kFlagStepped): its position,
  // whether it was a new one (neither stale nor held), and the client's force.
  static TickInput recorded(const telemetry::TickRecord& r, std::uint32_t periods) noexcept {
    return {r.position, (r.flags & (telemetry::kFlagStale | telemetry::kFlagHeld)) == 0, periods,
            r.client_force[0]};
  }
};

struct TickCommand {
  double command = 0.0;     // the force to write (0 when the law's force was not finite)
  double added = 0.0;       // the passivity controller's part of it
  double client = 0.0;      // a client's part of it (its share of the saturated sum)
  bool non_finite = false;  // the law computed a NaN or infinite force: the loop faults
  bool runaway = false;     // the runaway guard tripped (kFlagRunaway): the loop faults
};

// RT-safe: called every tick with a position. Observes the period just ended, steps the law,
// adds the passivity controller's damping and a client's force (saturated together to the
// law's max_force); fills the record's control fields (position, penetration, velocity,
// computed force, the law's flags, kFlagStepped, the observer's energy and damping, the
// client's force). The command is not yet in the record: the caller writes it, and after
// a fault writes zero instead.
TickCommand step_tick(control::Controller& law, control::PassivityObserver& observer,
                      const TickInput& in, telemetry::TickRecord& rec) noexcept;

// RT-safe: called every tick, with what was written (zero after a fault) and the client's part
// of it: the force the ZOH holds over the next period; the wall's share for its observer (a
// client's force has its own, loop/client_force.h).
inline void end_tick(control::PassivityObserver& observer, const TickCommand& written,
                     telemetry::TickRecord& rec) noexcept {
  rec.force_commanded = written.command;
  observer.commanded(written.command - written.client, written.added);
}

}  // namespace hapticd::loop
