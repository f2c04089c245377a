#include "loop/schedule.h"

#include <algorithm>

#include "base/clock.h"

namespace hapticd::loop {
namespace {

std::int32_t clamp_i32(std::int64_t v) noexcept {
  return static_cast<std::int32_t>(std::clamp<std::int64_t>(v, INT32_MIN, INT32_MAX));
}

}  // namespace

Schedule::Schedule(bool realtime, std::int64_t period_ns, int overrun_fault_streak) noexcept
    : realtime_(realtime),
      period_(period_ns),
      fault_streak_(overrun_fault_streak),
      start_(base::monotonic_ns()),
      deadline_(start_) {}

std::int64_t Schedule::wait(std::uint64_t tick, telemetry::TickRecord& rec) noexcept {
  std::int64_t wake = 0;
  if (realtime_) {
    base::sleep_until_ns(deadline_);
    wake = base::monotonic_ns();
    rec.scheduled_ns = deadline_ - start_;
    latency_ = wake - deadline_;
    rec.wake_latency_ns = clamp_i32(latency_);
  } else {
    wake = base::monotonic_ns();
    rec.scheduled_ns = static_cast<std::int64_t>(tick) * period_;  // k T, across runs
  }
  periods_ = static_cast<std::uint32_t>(
      last_scheduled_ < 0
          ? 1
          : std::max<std::int64_t>(1, (rec.scheduled_ns - last_scheduled_) / period_));
  last_scheduled_ = rec.scheduled_ns;
  return wake;
}

Fault Schedule::judge(std::uint64_t tick, std::int64_t wake, telemetry::TickRecord& rec,
                      std::int64_t& compute_ns) noexcept {
  const std::int64_t done = base::monotonic_ns();
  compute_ns = done - wake;
  overran_ = false;
  if (!realtime_) return {};
  rec.compute_ns = clamp_i32(compute_ns);
  if (done <= deadline_ + period_) {
    streak_ = 0;
    return {};
  }
  rec.flags |= telemetry::kFlagOverrun;
  overran_ = true;
  if (++streak_ >= fault_streak_) {
    return {FaultCause::kOverrunStreak, tick, static_cast<double>(streak_)};
  }
  return {};
}

std::int64_t Schedule::advance() noexcept {
  deadline_ += period_;
  if (!realtime_) return 0;
  // Late by whole periods: skip them, counted, rather than bursting to catch up.
  const std::int64_t late = base::monotonic_ns() - deadline_;
  if (late <= period_) return 0;
  const std::int64_t skip = late / period_;
  deadline_ += skip * period_;
  return skip;
}

}  // namespace hapticd::loop
