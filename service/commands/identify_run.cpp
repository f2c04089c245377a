#include "service/commands/identify_run.h"

#include <cmath>

#include "loop/rt_setup.h"
#include "loop/schedule.h"

namespace hapticd::service {
namespace {

using loop::FaultCause;

bool ended_by(loop::Fault f, ExcitationRecord& rec) noexcept {
  if (f.cause == FaultCause::kNone) return false;
  rec.fault = f;
  rec.end = ExcitationEnd::kFault;
  return true;
}

// One tick: read, check as the loop checks, record, write the planned force. False when it
// ends the excitation. RT-safe: called every tick.
bool tick(Device& device, double force, std::size_t k, std::int64_t wake, double max_travel,
          loop::SampleCheck& check, ExcitationRecord& rec) noexcept {
  PositionSample s;
  const IoStatus st = device.read(s);
  telemetry::TickRecord scratch;  // the checks mark a record; identify keeps its own
  const loop::Sensed sensed = check.check(k, wake, st, s, scratch);
  if (ended_by(sensed.fault, rec)) return false;
  // A held position (a device that reports on change) is as good a measurement as a new one.
  rec.valid[k] = sensed.has_position && !sensed.stale;
  rec.position[k] = sensed.has_position ? sensed.position : 0.0;
  if (rec.valid[k] && !rec.started) {
    rec.start = sensed.position;
    rec.started = true;
  }
  if (rec.started && std::abs(rec.position[k] - rec.start) > max_travel) {
    rec.end = ExcitationEnd::kTravel;
    return false;
  }
  const IoStatus ws = device.write(force);
  if (ws == IoStatus::kTransportFault || ws == IoStatus::kDeviceFault) {
    ended_by(
        {ws == IoStatus::kDeviceFault ? FaultCause::kDeviceReported : FaultCause::kTransportWrite,
         k, 0.0},
        rec);
    return false;
  }
  return true;
}

}  // namespace

ExcitationRecord::ExcitationRecord(std::size_t length)
    : position(length, 0.0), valid(length, false) {}

double ExcitationRecord::travel() const {
  double t = 0.0;
  for (std::size_t k = 0; k < ticks; ++k) {
    if (valid[k]) t = std::max(t, std::abs(position[k] - start));
  }
  return t;
}

void run_excitation(Device& device, std::span<const double> force, const ExcitationLimits& limits,
                    const std::atomic<bool>& stop, ExcitationRecord& rec) noexcept {
  loop::prefault_stack();
  loop::Schedule schedule(limits.samples.realtime, limits.samples.period_ns,
                          limits.overrun_fault_streak);
  loop::SampleCheck check(limits.samples);
  const std::size_t n = std::min(force.size(), rec.position.size());
  for (std::size_t k = 0; k < n; ++k) {
    telemetry::TickRecord timing;
    const std::int64_t wake = schedule.wait(k, timing);
    if (stop.load(std::memory_order_relaxed)) {
      rec.end = ExcitationEnd::kStopped;
      break;
    }
    if (!tick(device, force[k], k, wake, limits.max_travel, check, rec)) break;
    rec.ticks = k + 1;
    std::int64_t compute_ns = 0;
    if (ended_by(schedule.judge(k, wake, timing, compute_ns), rec)) break;
    check.skipped(schedule.advance());
  }
  device.write(0.0);
  device.disable();
}

}  // namespace hapticd::service
