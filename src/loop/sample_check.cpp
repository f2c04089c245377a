#include "loop/sample_check.h"

#include <algorithm>
#include <cmath>

#include "base/clock.h"

namespace hapticd::loop {
namespace {

using base::kNsPerS;

}  // namespace

SampleCheck::SampleCheck(const SampleLimits& limits) noexcept
    : limits_(limits),
      max_step_(limits.max_speed * static_cast<double>(limits.period_ns) / kNsPerS) {}

Sensed SampleCheck::stale_tick(std::uint64_t tick, telemetry::TickRecord& rec) noexcept {
  // Hold the last position (a ZOH on the measurement) and count the staleness; with no
  // position yet there is nothing to hold, and nothing is commanded.
  Sensed out;
  out.stale = true;
  out.position = last_x_;
  ++periods_since_x_;
  rec.flags |= telemetry::kFlagStale;
  if (++stale_streak_ >= limits_.stale_fault_ticks) {
    out.fault = {FaultCause::kStaleData, tick, static_cast<double>(stale_streak_)};
  }
  out.has_position = have_x_ && out.fault.cause == FaultCause::kNone;
  return out;
}

void SampleCheck::check_sequence(std::uint64_t tick, const PositionSample& sample, Sensed& out,
                                 telemetry::TickRecord& rec) noexcept {
  rec.sequence = static_cast<std::uint32_t>(sample.sequence);
  if (have_sequence_) {
    // How far the counter moved, against how many samples the driver took in since the last
    // tick (the newest and those it replaced): only numbers nobody received are a gap. A
    // counter that moved less (a device that repeats a sample) lost nothing.
    std::uint64_t advance = sample.sequence - last_sequence_;  // wraps like the counter
    if (limits_.sequence_modulus != 0) advance %= limits_.sequence_modulus;
    const std::uint64_t taken = std::max<std::uint32_t>(1, sample.samples);
    out.gap = advance > taken ? advance - taken : 0;
    if (out.gap > 0) {
      rec.flags |= telemetry::kFlagSequenceGap;
      rec.sequence_gap = static_cast<std::uint16_t>(std::min<std::uint64_t>(out.gap, 65535));
      if (limits_.sequence_gap_fault != 0 && out.gap >= limits_.sequence_gap_fault) {
        out.fault = {FaultCause::kSequenceGap, tick, static_cast<double>(out.gap)};
        return;
      }
    }
  }
  last_sequence_ = sample.sequence;
  have_sequence_ = true;
}

bool SampleCheck::too_fast(std::uint64_t tick, const PositionSample& sample, bool has_time,
                           Sensed& out) const noexcept {
  // Judge the speed over the time that really passed: the periods since the last new sample
  // (stale reads, skipped periods), or the samples' own times when they span more. Never
  // less: an encoder's sample time is its last edge's, and one count between two edges
  // microseconds apart (a line dithering at a count boundary, or edge times an interrupt
  // thread stamped late together) is quantisation, not an impossible speed.
  const double jump = std::abs(sample.position - last_x_);
  double spanned = static_cast<double>(periods_since_x_);
  if (limits_.realtime && has_time && last_time_ns_ > 0 && sample.time_ns > last_time_ns_) {
    spanned = std::max(spanned, static_cast<double>(sample.time_ns - last_time_ns_) /
                                    static_cast<double>(limits_.period_ns));
  }
  if (!have_x_ || jump <= max_step_ * spanned) return false;
  out.fault = {FaultCause::kEncoderJump, tick,
               jump * kNsPerS / (spanned * static_cast<double>(limits_.period_ns))};
  return true;
}

Sensed SampleCheck::check(std::uint64_t tick, std::int64_t wake_ns, IoStatus status,
                          PositionSample& sample, telemetry::TickRecord& rec) noexcept {
  rec.device_status = sample.status;
  Sensed out;
  if (status == IoStatus::kTransportFault || status == IoStatus::kDeviceFault) {
    out.fault = {
        status == IoStatus::kDeviceFault ? FaultCause::kDeviceReported : FaultCause::kTransportRead,
        tick, 0.0};
    return out;
  }
  const bool has_seq = (sample.flags & kSampleHasSequence) != 0;
  // The same sample handed over again is no new data, whatever the status said.
  if (status != IoStatus::kOk || (has_seq && have_sequence_ && sample.sequence == last_sequence_)) {
    out = stale_tick(tick, rec);
    sample.position = out.position;
    return out;
  }
  stale_streak_ = 0;
  if ((sample.flags & kSampleHeld) != 0 && have_x_) {
    // The same position, current but not measured anew: no staleness, and the next measured
    // sample's move is judged over the whole time since the last one.
    ++periods_since_x_;
    rec.flags |= telemetry::kFlagHeld;
    sample.position = last_x_;
    out.position = last_x_;
    out.has_position = true;
    return out;
  }
  const bool has_time = (sample.flags & kSampleHasTime) != 0 && sample.time_ns > 0;
  if (has_time) rec.sample_time_ns = sample.time_ns;
  // A sample measured long ago is as stale as none (realtime: freerun has no real clock).
  if (limits_.realtime && has_time &&
      wake_ns - sample.time_ns >= limits_.stale_fault_ticks * limits_.period_ns) {
    out.fault = {FaultCause::kStaleData, tick,
                 std::floor(static_cast<double>(wake_ns - sample.time_ns) /
                            static_cast<double>(limits_.period_ns))};
    return out;
  }
  if (has_seq) {
    check_sequence(tick, sample, out, rec);
    if (out.fault.cause != FaultCause::kNone) return out;
  }
  if (!std::isfinite(sample.position)) {
    out.fault = {FaultCause::kNonFinitePosition, tick, sample.position};
    return out;
  }
  if (too_fast(tick, sample, has_time, out)) return out;
  last_x_ = sample.position;
  have_x_ = true;
  periods_since_x_ = 1;
  last_time_ns_ = has_time ? sample.time_ns : 0;
  out.position = sample.position;
  out.has_position = true;
  out.fresh = true;
  return out;
}

}  // namespace hapticd::loop
