// The tick loop of `hapticd identify`: the planned force written every tick, the positions
// recorded, and every way it ends (the excitation done, a fault, the device past --max-travel,
// a stop) ends with zero force written and output off. It keeps time and checks every sample
// exactly as `hapticd run` does, by running the loop's own Schedule and SampleCheck: stale
// data, a sample that old, sequence gaps, non-finite positions, safety.max_speed and a streak
// of overruns fault it as they fault a run.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <span>
#include <vector>

#include "drivers/device.h"
#include "loop/loop_fault.h"
#include "loop/sample_check.h"

namespace hapticd::service {

enum class ExcitationEnd { kDone, kFault, kTravel, kStopped };

struct ExcitationRecord {
  std::vector<double> position;  // x_k (held over a tick without a fresh sample)
  std::vector<bool> valid;       // a fresh sample at tick k
  std::size_t ticks = 0;         // ticks run
  // The joint excited, whose positions these are (< the device's joints: the command checks).
  std::size_t joint = 0;
  // Each joint's first position read, once it has one.
  std::array<double, base::kMaxJoints> start{};
  std::array<bool, base::kMaxJoints> started{};
  ExcitationEnd end = ExcitationEnd::kDone;
  loop::Fault fault;  // what faulted it (ExcitationEnd::kFault), as the loop names faults

  // Not RT-safe: sizes everything for `ticks` before the first tick.
  explicit ExcitationRecord(std::size_t length, std::size_t excited = 0);
  // The farthest the excited joint went from where it started (m or rad).
  double travel() const;
};

// How the excitation keeps time and checks samples: the loop's own limits.
struct ExcitationLimits {
  loop::SampleLimits samples;     // realtime: an absolute CLOCK_MONOTONIC schedule
  int overrun_fault_streak = 10;  // loop.overrun_fault_streak
  double max_travel = 0.1;        // m (rad) from where it started (--max-travel), every joint
};

// Drives `force` (one value a tick) on rec.joint, zero on the device's other joints, and
// records that joint's positions into `rec` (every joint's sample checked as the loop checks
// it, and held within max_travel); then writes zero and disables output, whatever ended it.
// Realtime: ticks on an absolute schedule of the limits' period; otherwise back to back (a
// simulated device, paced by its peer). `stop` is read once a tick. RT-safe: nothing allocated,
// locked, logged or thrown while it runs.
void run_excitation(Device& device, std::span<const double> force, const ExcitationLimits& limits,
                    const std::atomic<bool>& stop, ExcitationRecord& rec) noexcept;

}  // namespace hapticd::service
