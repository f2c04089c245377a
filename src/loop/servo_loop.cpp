// The tick, and everything it touches. The RT working set is kept small and listed here, so a
// change that adds to it is seen: the Device (its state, the driver's buffers), the
// Controller (ControlLaw and three 16-tap histories, the delay line), the PassivityObserver
// (two command histories as long as the device's delay, allocated before the loop), this
// ServoLoop (options, two 4 KB LatencyHistograms, counters, the LiveStatus atomics), the
// LawSwap mailbox (one atomic load a tick), the SenseState and TickRecord on the stack, and
// one slot of the SPSC ring. Nothing else: no allocation, no lock, no log, no throw.
#include "loop/servo_loop.h"

#include <sched.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

#include "base/clock.h"
#include "loop/rt_setup.h"

namespace hapticd::loop {
namespace {

// The controller's flags are copied into the tick record unchanged.
constexpr bool same_bit(control::ControlFlag c, telemetry::TickFlag t) {
  return static_cast<std::uint32_t>(c) == static_cast<std::uint32_t>(t);
}
static_assert(same_bit(control::kControlContact, telemetry::kFlagContact));
static_assert(same_bit(control::kControlSaturated, telemetry::kFlagSaturated));
static_assert(same_bit(control::kControlNoPullClamped, telemetry::kFlagNoPullClamped));
static_assert(same_bit(control::kControlUnarmed, telemetry::kFlagUnarmed));
static_assert(same_bit(control::kControlNonFinite, telemetry::kFlagNonFinite));

constexpr std::int64_t kNsPerS = 1'000'000'000;

std::int64_t now_ns() noexcept { return base::monotonic_ns(); }
void sleep_until(std::int64_t deadline_ns) noexcept { base::sleep_until_ns(deadline_ns); }

std::int32_t clamp_i32(std::int64_t v) noexcept {
  return static_cast<std::int32_t>(std::clamp<std::int64_t>(v, INT32_MIN, INT32_MAX));
}

control::ObserverParams with_period(control::ObserverParams p, std::int64_t period_ns) {
  p.sample_period = static_cast<double>(period_ns) / kNsPerS;
  return p;
}

}  // namespace

ServoLoop::ServoLoop(Device& device, control::Controller& controller,
                     telemetry::SpscRing<telemetry::TickRecord>* ring, const LoopOptions& options)
    : device_(device),
      controller_(&controller),
      ring_(ring),
      options_(options),
      max_step_(options.max_speed * static_cast<double>(options.period_ns) / kNsPerS),
      observer_(with_period(options.observer, options.period_ns)) {}

void ServoLoop::set_fault(Fault f, telemetry::TickRecord& rec, LoopResult& res) const noexcept {
  res.fault = f;
  rec.flags |= telemetry::kFlagFault;
  rec.fault_cause = static_cast<std::uint8_t>(f.cause);
  if (f.cause == FaultCause::kTransportRead || f.cause == FaultCause::kTransportWrite ||
      f.cause == FaultCause::kDeviceReported) {
    const DeviceFault df = device_.fault();
    rec.fault_class = static_cast<std::uint8_t>(df.fault_class);
    rec.fault_code = df.code;
  }
}

void ServoLoop::log(const telemetry::TickRecord& rec, const std::atomic<bool>& stop) noexcept {
  if (ring_ == nullptr) return;
  while (options_.wait_for_ring && ring_->size_approx() >= ring_->capacity() &&
         !stop.load(std::memory_order_relaxed)) {
    sched_yield();
  }
  ring_->try_push(rec);  // realtime: a full ring counts the loss, never blocks
}

void ServoLoop::take_reloads(std::uint64_t tick, std::int64_t scheduled_ns, LoopResult& res,
                             const std::atomic<bool>& stop) noexcept {
  if (options_.law_swap == nullptr) return;
  telemetry::TickRecord marker;
  marker.tick = tick;
  marker.scheduled_ns = scheduled_ns;
  if (control::Controller* next = options_.law_swap->take(controller_, tick)) {
    controller_ = next;
    ++res.reloads;
    live_.reloads.store(res.reloads, std::memory_order_relaxed);
    marker.marker = telemetry::kMarkerReloadAccepted;
    log(marker, stop);
  }
  for (std::uint32_t n = options_.law_swap->take_refusals(); n > 0; --n) {
    marker.marker = telemetry::kMarkerReloadRefused;
    log(marker, stop);
  }
}

void ServoLoop::mark_rearmed(const std::atomic<bool>& stop) noexcept {
  telemetry::TickRecord rearmed;
  rearmed.tick = next_tick_;
  rearmed.scheduled_ns =
      options_.realtime ? 0 : static_cast<std::int64_t>(next_tick_) * options_.period_ns;
  rearmed.marker = telemetry::kMarkerRearmed;
  log(rearmed, stop);
}

void ServoLoop::publish(const telemetry::TickRecord& rec, const LoopResult& res) noexcept {
  constexpr auto r = std::memory_order_relaxed;
  live_.overruns.store(res.overruns, r);
  live_.missed_ticks.store(res.missed_ticks, r);
  live_.stale_ticks.store(res.stale_ticks, r);
  live_.contact_ticks.store(res.contact_ticks, r);
  live_.position.store(rec.position, r);
  live_.penetration.store(rec.penetration, r);
  live_.force_commanded.store(rec.force_commanded, r);
  live_.wall_energy_j.store(observer_.wall_work_j(), r);
  live_.observer_energy_j.store(observer_.energy_j(), r);
  live_.damped_ticks.store(observer_.damped_ticks(), r);
}

PassivityResult ServoLoop::passivity() const noexcept {
  PassivityResult p;
  p.observed = observer_.enabled();
  p.energy_j = observer_.energy_j();
  p.min_energy_j = observer_.min_energy_j();
  p.negative_ticks = observer_.negative_ticks();
  p.damped_ticks = observer_.damped_ticks();
  p.max_damping = observer_.max_alpha();
  p.damping_work_j = observer_.damping_work_j();
  return p;
}

control::Damping ServoLoop::control(std::uint64_t tick, const PositionSample& sample, bool fresh,
                                    std::uint32_t periods, telemetry::TickRecord& rec,
                                    LoopResult& res) noexcept {
  observer_.observe(sample.position, fresh, periods);
  rec.flags |= telemetry::kFlagStepped;
  const control::ControlOutput out = controller_->step(sample.position);
  rec.position = sample.position;
  rec.penetration = out.penetration;
  rec.velocity = out.velocity;
  rec.force_computed = out.force_computed;
  rec.flags |= out.flags;
  rec.observer_energy_j = observer_.energy_j();
  if (out.flags & control::kControlNonFinite) {
    set_fault({FaultCause::kNonFiniteForce, tick, out.force_computed}, rec, res);
    return {};
  }
  const control::Damping d = observer_.damp(out.force_commanded, controller_->law());
  if (d.alpha > 0.0) {
    rec.flags |= telemetry::kFlagPassivityDamped;
    rec.passivity_damping = d.alpha;
    if (d.saturated) rec.flags |= telemetry::kFlagSaturated;
  }
  return d;
}

bool ServoLoop::check_sequence(std::uint64_t tick, const PositionSample& sample, SenseState& st,
                               telemetry::TickRecord& rec, LoopResult& res) noexcept {
  rec.sequence = static_cast<std::uint32_t>(sample.sequence);
  if (st.have_sequence) {
    // How far the counter moved, against how many samples the driver took in since the last
    // tick (the newest and those it replaced): only numbers nobody received are a gap. A
    // counter that moved less (a device that repeats a sample) lost nothing.
    std::uint64_t advance = sample.sequence - st.last_sequence;  // wraps like the counter
    if (options_.sequence_modulus != 0) advance %= options_.sequence_modulus;
    const std::uint64_t taken = std::max<std::uint32_t>(1, sample.samples);
    const std::uint64_t gap = advance > taken ? advance - taken : 0;
    if (gap > 0) {
      rec.flags |= telemetry::kFlagSequenceGap;
      rec.sequence_gap = static_cast<std::uint16_t>(std::min<std::uint64_t>(gap, 65535));
      ++res.sequence_gaps;
      res.samples_missed += gap;
      if (options_.sequence_gap_fault != 0 && gap >= options_.sequence_gap_fault) {
        set_fault({FaultCause::kSequenceGap, tick, static_cast<double>(gap)}, rec, res);
        return false;
      }
    }
  }
  st.last_sequence = sample.sequence;
  st.have_sequence = true;
  return true;
}

bool ServoLoop::sense(std::uint64_t tick, std::int64_t wake_ns, PositionSample& sample,
                      SenseState& st, telemetry::TickRecord& rec, LoopResult& res) noexcept {
  const IoStatus rs = device_.read(sample);
  rec.device_status = sample.status;
  if (rs == IoStatus::kTransportFault || rs == IoStatus::kDeviceFault) {
    set_fault(
        {rs == IoStatus::kDeviceFault ? FaultCause::kDeviceReported : FaultCause::kTransportRead,
         tick, 0.0},
        rec, res);
    return false;
  }
  const bool has_seq = (sample.flags & kSampleHasSequence) != 0;
  // The same sample handed over again is no new data, whatever the status said.
  if (rs != IoStatus::kOk || (has_seq && st.have_sequence && sample.sequence == st.last_sequence)) {
    // Hold the last position (a ZOH on the measurement) and count the staleness; with no
    // position yet there is nothing to hold, and nothing is commanded.
    ++res.stale_ticks;
    ++st.periods_since_x;
    st.fresh = false;
    rec.flags |= telemetry::kFlagStale;
    sample.position = st.last_x;
    if (++st.stale_streak >= options_.stale_fault_ticks) {
      set_fault({FaultCause::kStaleData, tick, static_cast<double>(st.stale_streak)}, rec, res);
    }
    return st.have_x && res.fault.cause == FaultCause::kNone;
  }
  st.stale_streak = 0;
  if ((sample.flags & kSampleHeld) != 0 && st.have_x) {
    // The same position, current but not measured anew: no staleness, and the next measured
    // sample's move is judged over the whole time since the last one.
    ++st.periods_since_x;
    st.fresh = false;
    sample.position = st.last_x;
    return true;
  }
  st.fresh = true;
  const bool has_time = (sample.flags & kSampleHasTime) != 0 && sample.time_ns > 0;
  if (has_time) rec.sample_time_ns = sample.time_ns;
  // A sample measured long ago is as stale as none (realtime: freerun has no real clock).
  if (options_.realtime && has_time &&
      wake_ns - sample.time_ns >= options_.stale_fault_ticks * options_.period_ns) {
    set_fault({FaultCause::kStaleData, tick,
               std::floor(static_cast<double>(wake_ns - sample.time_ns) /
                          static_cast<double>(options_.period_ns))},
              rec, res);
    return false;
  }
  if (has_seq && !check_sequence(tick, sample, st, rec, res)) return false;
  if (!std::isfinite(sample.position)) {
    set_fault({FaultCause::kNonFinitePosition, tick, sample.position}, rec, res);
    return false;
  }
  // Judge the speed over the time that really passed: the periods since the last new sample
  // (stale reads, skipped periods), or the samples' own times when they span more. Never
  // less: an encoder's sample time is its last edge's, and one count between two edges
  // microseconds apart (a line dithering at a count boundary, or edge times an interrupt
  // thread stamped late together) is quantisation, not an impossible speed.
  const double jump = std::abs(sample.position - st.last_x);
  double spanned = static_cast<double>(st.periods_since_x);
  if (options_.realtime && has_time && st.last_time_ns > 0 && sample.time_ns > st.last_time_ns) {
    spanned = std::max(spanned, static_cast<double>(sample.time_ns - st.last_time_ns) /
                                    static_cast<double>(options_.period_ns));
  }
  if (st.have_x && jump > max_step_ * spanned) {
    set_fault({FaultCause::kEncoderJump, tick,
               jump * kNsPerS / (spanned * static_cast<double>(options_.period_ns))},
              rec, res);
    return false;
  }
  st.last_x = sample.position;
  st.have_x = true;
  st.periods_since_x = 1;
  st.last_time_ns = has_time ? sample.time_ns : 0;
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
  std::int64_t last_scheduled = -1;
  observer_.restart();  // nothing in flight from an earlier run
  const double work_before = observer_.wall_work_j();
  if (next_tick_ > 0) mark_rearmed(stop);  // enabled again after a fault

  for (std::uint64_t n = 0;; ++n) {
    if (stop.load(std::memory_order_relaxed)) break;
    if (options_.max_ticks != 0 && n >= options_.max_ticks) break;
    const std::uint64_t tick = next_tick_ + n;

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
      rec.scheduled_ns = static_cast<std::int64_t>(tick) * period;  // k T, across runs
    }

    take_reloads(tick, rec.scheduled_ns, res, stop);
    // Sample periods since the previous tick: more than one after skipped periods.
    const auto periods = static_cast<std::uint32_t>(
        last_scheduled < 0
            ? 1
            : std::max<std::int64_t>(1, (rec.scheduled_ns - last_scheduled) / period));
    last_scheduled = rec.scheduled_ns;
    PositionSample sample;
    const bool stepped = sense(tick, wake, sample, st, rec, res);
    if (!stepped && res.fault.cause == FaultCause::kNone) rec.flags |= telemetry::kFlagNoPosition;
    const control::Damping d =
        stepped ? control(tick, sample, st.fresh, periods, rec, res) : control::Damping{};
    double command = d.command;
    double added = d.added;
    if (res.fault.cause == FaultCause::kNone) {
      const IoStatus ws = device_.write(command);
      if (ws == IoStatus::kTransportFault || ws == IoStatus::kDeviceFault) {
        set_fault({ws == IoStatus::kDeviceFault ? FaultCause::kDeviceReported
                                                : FaultCause::kTransportWrite,
                   tick, 0.0},
                  rec, res);
      }
    }
    if (res.fault.cause != FaultCause::kNone) {
      command = 0.0;
      added = 0.0;
      device_.write(0.0);  // zero force at once; the service then disables output
    }
    rec.force_commanded = command;
    observer_.commanded(command, added);

    // Bookkeeping after the timed window.
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
          set_fault({FaultCause::kOverrunStreak, tick, static_cast<double>(overrun_streak)}, rec,
                    res);
          device_.write(0.0);
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
    log(rec, stop);
    publish(rec, res);
    ++res.ticks;
    ticks_done_.store(next_tick_ + res.ticks, std::memory_order_relaxed);
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
  if (options_.law_swap != nullptr) options_.law_swap->loop_ended();  // no more takes
  next_tick_ += res.ticks;
  res.wall_energy_j = observer_.wall_work_j() - work_before;
  res.passivity = passivity();
  return res;
}

}  // namespace hapticd::loop
