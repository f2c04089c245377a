// The checks every tick makes on what the device read (docs/architecture.md): no new position
// for safety.stale_fault_ticks ticks (or a sample that old), a gap in the device's own
// sequence, a non-finite position, a move faster than safety.max_speed. A value with its own
// state and no clock, device or ring, so `hapticd run` and `hapticd identify` apply the same
// checks by calling the same code.
#pragma once

#include <cstdint>

#include "drivers/device.h"
#include "loop/loop_fault.h"
#include "telemetry/tick_record.h"

namespace hapticd::loop {

// What a sample is checked against: safety.* and what the device declared.
struct SampleLimits {
  bool realtime = true;  // samples carry real times (freerun: no real clock to judge them by)
  std::int64_t period_ns = 1'000'000;
  int stale_fault_ticks = 3;  // ticks without new data (or a sample that old) that fault
  double max_speed = 10.0;    // m/s; a faster jump between samples is an encoder fault
  // A gap of this many samples or more in the device's sequence faults; 0: counted only.
  std::uint32_t sequence_gap_fault = 1;
  std::uint64_t sequence_modulus = 0;  // DeviceInfo::sequence_modulus: 0 for a 64-bit counter
};

// What the checks made of one read.
struct Sensed {
  double position = 0.0;      // what the law acts on: the sample's, or the last one held
  bool has_position = false;  // false: nothing to act on (none yet, or a fault)
  bool fresh = false;         // a new measurement (not held, not stale)
  bool stale = false;         // no new data this tick (counted, kFlagStale)
  std::uint64_t gap = 0;      // samples the device's sequence skipped before this one
  Fault fault;                // kNone unless the read or the sample faults the loop
};

class SampleCheck {
 public:
  explicit SampleCheck(const SampleLimits& limits) noexcept;

  // RT-safe: called every tick. `status` and `sample` are what Device::read gave at `wake_ns`
  // (a held or stale tick's position is replaced by the last one). Sets the record's sample
  // fields and its stale, held and sequence-gap flags; a fault is returned, not recorded.
  Sensed check(std::uint64_t tick, std::int64_t wake_ns, IoStatus status, PositionSample& sample,
               telemetry::TickRecord& rec) noexcept;
  // RT-safe. Whole periods the schedule skipped: the next sample's move spans them too.
  void skipped(std::int64_t periods) noexcept { periods_since_x_ += periods; }

 private:
  Sensed stale_tick(std::uint64_t tick, telemetry::TickRecord& rec) noexcept;
  // A new sample's sequence number against the last one: the gap, and a fault past the limit.
  void check_sequence(std::uint64_t tick, const PositionSample& sample, Sensed& out,
                      telemetry::TickRecord& rec) noexcept;
  // A new sample's move against safety.max_speed, over the time that really passed.
  bool too_fast(std::uint64_t tick, const PositionSample& sample, bool has_time,
                Sensed& out) const noexcept;

  SampleLimits limits_;
  double max_step_;  // max_speed * T: cached so the check multiplies, not divides
  double last_x_ = 0.0;
  bool have_x_ = false;
  int stale_streak_ = 0;
  std::int64_t periods_since_x_ = 1;  // periods the next new sample spans
  std::int64_t last_time_ns_ = 0;     // the last sample's own time (0: it had none)
  std::uint64_t last_sequence_ = 0;
  bool have_sequence_ = false;
};

}  // namespace hapticd::loop
