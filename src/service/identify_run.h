// The tick loop of `hapticd identify`: the planned force written every tick, the positions
// recorded, and every way it ends (the excitation done, a device fault, stale or non-finite
// data, the device past --max-travel, a stop) ends with zero force written and output off.
#pragma once

#include <atomic>
#include <cstddef>
#include <span>
#include <vector>

#include "drivers/device.h"

namespace hapticd::service {

enum class ExcitationEnd { kDone, kDeviceFault, kStale, kNonFinite, kTravel, kStopped };

struct ExcitationRecord {
  std::vector<double> position;  // x_k (held over a tick without a fresh sample)
  std::vector<bool> valid;       // a fresh sample at tick k
  std::size_t ticks = 0;         // ticks run
  double start = 0.0;            // the first position read
  bool started = false;
  ExcitationEnd end = ExcitationEnd::kDone;

  // Not RT-safe: sizes everything for `ticks` before the first tick.
  explicit ExcitationRecord(std::size_t length);
  // The farthest the device went from where it started (m).
  double travel() const;
};

// Drives `force` (one value a tick) and records into `rec`; then writes zero and disables
// output, whatever ended it. Realtime: ticks on an absolute CLOCK_MONOTONIC schedule of
// `period_s`; otherwise back to back (a simulated device, paced by its peer). `stop` is read
// once a tick. RT-safe: nothing allocated, locked, logged or thrown while it runs.
void run_excitation(Device& device, std::span<const double> force, double period_s, bool realtime,
                    double max_travel, const std::atomic<bool>& stop,
                    ExcitationRecord& rec) noexcept;

}  // namespace hapticd::service
