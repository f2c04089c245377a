#include "loop/servo_loop.h"

#include <sched.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

#include "loop/rt_setup.h"

namespace hapticd::loop {
namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;

std::int64_t now_ns() noexcept {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

void sleep_until(std::int64_t deadline_ns) noexcept {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(deadline_ns / kNsPerS);
  ts.tv_nsec = static_cast<long>(deadline_ns % kNsPerS);
  // Absolute time: a signal interrupting the sleep does not move the deadline.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

std::int32_t clamp_i32(std::int64_t v) noexcept {
  return static_cast<std::int32_t>(std::clamp<std::int64_t>(v, INT32_MIN, INT32_MAX));
}

}  // namespace

ServoLoop::ServoLoop(Device& device, control::Controller& controller,
                     telemetry::SpscRing<telemetry::TickRecord>* ring, const LoopOptions& options)
    : device_(device),
      controller_(controller),
      ring_(ring),
      options_(options),
      max_step_(options.max_speed * static_cast<double>(options.period_ns) / kNsPerS) {}

bool ServoLoop::sense(std::uint64_t tick, PositionSample& sample, SenseState& st,
                      telemetry::TickRecord& rec, LoopResult& res) noexcept {
  const IoStatus rs = device_.read(sample);
  rec.device_status = sample.device_status;
  if (rs == IoStatus::kError) {
    res.fault = {FaultCause::kDeviceRead, tick, 0.0};
    return false;
  }
  if (rs == IoStatus::kNoNewData) {
    // Hold the last position (a ZOH on the measurement) and count the staleness; with no
    // position yet there is nothing to hold, and nothing is commanded.
    ++res.stale_ticks;
    ++st.periods_since_x;
    rec.flags |= telemetry::kFlagStale;
    sample.position = st.last_x;
    if (++st.stale_streak >= options_.stale_fault_ticks) {
      res.fault = {FaultCause::kStaleData, tick, static_cast<double>(st.stale_streak)};
    }
    return st.have_x && res.fault.cause == FaultCause::kNone;
  }
  st.stale_streak = 0;
  if (!std::isfinite(sample.position)) {
    res.fault = {FaultCause::kNonFinitePosition, tick, sample.position};
    return false;
  }
  // A new sample may span several periods (stale reads, skipped periods): judge its speed
  // over the time that really passed.
  const double jump = std::abs(sample.position - st.last_x);
  const auto spanned = static_cast<double>(st.periods_since_x);
  if (st.have_x && jump > max_step_ * spanned) {
    res.fault = {FaultCause::kEncoderJump, tick,
                 jump * kNsPerS / (spanned * static_cast<double>(options_.period_ns))};
    return false;
  }
  st.last_x = sample.position;
  st.have_x = true;
  st.periods_since_x = 1;
  return true;
}

LoopResult ServoLoop::run(const std::atomic<bool>& stop) noexcept {
  prefault_stack();
  LoopResult res;
  const std::int64_t period = options_.period_ns;
  const std::int64_t start = now_ns();
  std::int64_t deadline = start;  // the first tick is due at once
  int overrun_streak = 0;
  SenseState st;

  for (std::uint64_t tick = 0;; ++tick) {
    if (stop.load(std::memory_order_relaxed)) break;
    if (options_.max_ticks != 0 && tick >= options_.max_ticks) break;

    telemetry::TickRecord rec;
    rec.tick = tick;
    std::int64_t wake = 0;
    if (options_.realtime) {
      sleep_until(deadline);
      wake = now_ns();
      rec.scheduled_ns = deadline - start;
      rec.wake_latency_ns = clamp_i32(wake - deadline);
    } else {
      wake = now_ns();
      rec.scheduled_ns = static_cast<std::int64_t>(tick) * period;
    }

    PositionSample sample;
    double command = 0.0;
    if (sense(tick, sample, st, rec, res)) {
      const control::ControlOutput out = controller_.step(sample.position);
      command = out.force_commanded;
      rec.position = sample.position;
      rec.penetration = out.penetration;
      rec.velocity = out.velocity;
      rec.force_computed = out.force_computed;
      rec.flags |= out.flags;
      if (out.flags & telemetry::kFlagNonFinite) {
        res.fault = {FaultCause::kNonFiniteForce, tick, out.force_computed};
      }
    }
    if (res.fault.cause == FaultCause::kNone && device_.write(command) == IoStatus::kError) {
      res.fault = {FaultCause::kDeviceWrite, tick, 0.0};
    }
    if (res.fault.cause != FaultCause::kNone) {
      command = 0.0;
      device_.write(0.0);  // zero force at once; the service then disables output
      rec.flags |= telemetry::kFlagFault;
    }
    rec.force_commanded = command;

    // Bookkeeping after the timed window: the histograms are cold memory after a sleep.
    const std::int64_t done = now_ns();
    compute_time_.record(done - wake);
    if (options_.realtime) {
      wake_latency_.record(wake - deadline);
      rec.compute_ns = clamp_i32(done - wake);
      if (done > deadline + period) {
        rec.flags |= telemetry::kFlagOverrun;
        ++res.overruns;
        if (++overrun_streak >= options_.overrun_fault_streak &&
            res.fault.cause == FaultCause::kNone) {
          res.fault = {FaultCause::kOverrunStreak, tick, static_cast<double>(overrun_streak)};
          device_.write(0.0);
          rec.flags |= telemetry::kFlagFault;
          rec.force_commanded = 0.0;
        }
      } else {
        overrun_streak = 0;
      }
    }

    if (rec.flags & telemetry::kFlagContact) ++res.contact_ticks;
    if (rec.flags & telemetry::kFlagSaturated) ++res.saturated_ticks;
    if (rec.flags & telemetry::kFlagUnarmed) ++res.unarmed_ticks;
    res.max_penetration = std::max(res.max_penetration, rec.penetration);
    if (ring_ != nullptr) {
      while (options_.wait_for_ring && ring_->size_approx() >= ring_->capacity() &&
             !stop.load(std::memory_order_relaxed)) {
        sched_yield();
      }
      ring_->try_push(rec);  // realtime: a full ring counts the loss, never blocks
    }
    ++res.ticks;
    ticks_done_.store(res.ticks, std::memory_order_relaxed);
    if (res.fault.cause != FaultCause::kNone) break;

    deadline += period;
    if (options_.realtime) {
      // Late by whole periods: skip them, counted, rather than bursting to catch up.
      const std::int64_t late = now_ns() - deadline;
      if (late > period) {
        const std::int64_t skip = late / period;
        res.missed_ticks += static_cast<std::uint64_t>(skip);
        st.periods_since_x += skip;
        deadline += skip * period;
      }
    }
  }
  device_.write(0.0);  // the last command must not outlive the loop that was servoing it
  return res;
}

}  // namespace hapticd::loop
