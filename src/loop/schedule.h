// The loop's clock (docs/architecture.md): realtime sleeps to an absolute CLOCK_MONOTONIC
// deadline every period and judges each tick against it (overruns, a streak of them is a
// fault, whole periods late are skipped rather than burst through); freerun never sleeps and
// stamps tick k at k T, so no host timing enters a simulated run. `hapticd run` and
// `hapticd identify` keep time with the same schedule.
#pragma once

#include <cstdint>

#include "loop/loop_fault.h"
#include "telemetry/tick_record.h"

namespace hapticd::loop {

class Schedule {
 public:
  // RT-safe. Starts now: the first tick is due at once.
  Schedule(bool realtime, std::int64_t period_ns, int overrun_fault_streak) noexcept;

  // RT-safe: called every tick, first. Sleeps to the tick's deadline (realtime) and returns
  // the wake time; sets the record's scheduled_ns and wake latency.
  std::int64_t wait(std::uint64_t tick, telemetry::TickRecord& rec) noexcept;
  // RT-safe. Sample periods since the previous tick: more than one after skipped periods.
  std::uint32_t periods() const noexcept { return periods_; }
  // RT-safe: called every tick, last, with its wake time. Sets the compute time and the
  // overrun flag; a streak of loop.overrun_fault_streak overruns is the returned fault. The
  // time taken is returned through `compute_ns` for the histograms.
  Fault judge(std::uint64_t tick, std::int64_t wake, telemetry::TickRecord& rec,
              std::int64_t& compute_ns) noexcept;
  // RT-safe. On to the next deadline; returns the whole periods skipped because the tick
  // ended that late (realtime only; they are counted, not caught up).
  std::int64_t advance() noexcept;
  bool overran() const noexcept { return overran_; }
  // RT-safe. The last wake's time past its deadline (realtime), unclamped.
  std::int64_t latency() const noexcept { return latency_; }

 private:
  bool realtime_;
  std::int64_t period_;
  int fault_streak_;
  std::int64_t start_;
  std::int64_t deadline_;
  std::int64_t last_scheduled_ = -1;
  std::uint32_t periods_ = 1;
  std::int64_t latency_ = 0;
  int streak_ = 0;
  bool overran_ = false;
};

}  // namespace hapticd::loop
