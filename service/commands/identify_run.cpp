#include "service/commands/identify_run.h"

#include <array>
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

using Checks = std::array<loop::SampleCheck, base::kMaxJoints>;

// Whether any joint's sample ended it (a fault, or past max_travel from where it started);
// `out` the excited joint's, checked. RT-safe: called every tick.
bool read_joints(Device& device, std::size_t k, std::int64_t wake, std::uint32_t periods,
                 const ExcitationLimits& limits, Checks& checks, ExcitationRecord& rec,
                 loop::Sensed& out) noexcept {
  std::array<PositionSample, base::kMaxJoints> s{};
  const std::size_t n = device.info().joints;
  const IoStatus st = device.read(std::span<PositionSample>(s.data(), n), periods);
  for (std::size_t j = 0; j < n; ++j) {
    telemetry::TickRecord scratch;  // the checks mark a record; identify keeps its own
    const loop::Sensed sensed = checks[j].check(k, wake, st, s[j], scratch);
    if (ended_by(sensed.fault, rec)) return true;
    if (j == rec.joint) out = sensed;
    if (!sensed.has_position || sensed.stale) continue;
    if (!rec.started[j]) rec.start[j] = sensed.position;
    rec.started[j] = true;
    if (std::abs(sensed.position - rec.start[j]) > limits.max_travel) {
      rec.end = ExcitationEnd::kTravel;
      return true;
    }
  }
  return false;
}

// One tick: read, check as the loop checks, record, write the planned force on the excited
// joint and zero on the others. False when it ends the excitation. RT-safe: called every tick.
bool tick(Device& device, double force, std::size_t k, std::int64_t wake, std::uint32_t periods,
          const ExcitationLimits& limits, Checks& checks, ExcitationRecord& rec) noexcept {
  loop::Sensed sensed;
  if (read_joints(device, k, wake, periods, limits, checks, rec, sensed)) return false;
  // A held position (a device that reports on change) is as good a measurement as a new one.
  rec.valid[k] = sensed.has_position && !sensed.stale;
  rec.position[k] = sensed.has_position ? sensed.position : 0.0;
  std::array<double, base::kMaxJoints> forces{};
  forces[rec.joint] = force;
  const IoStatus ws = device.write(std::span<const double>(forces.data(), device.info().joints));
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

ExcitationRecord::ExcitationRecord(std::size_t length, std::size_t excited)
    : position(length, 0.0), valid(length, false), joint(excited) {}

double ExcitationRecord::travel() const {
  double t = 0.0;
  for (std::size_t k = 0; k < ticks; ++k) {
    if (valid[k]) t = std::max(t, std::abs(position[k] - start[joint]));
  }
  return t;
}

void run_excitation(Device& device, std::span<const double> force, const ExcitationLimits& limits,
                    const std::atomic<bool>& stop, ExcitationRecord& rec) noexcept {
  loop::prefault_stack();
  loop::Schedule schedule(limits.samples.realtime, limits.samples.period_ns,
                          limits.overrun_fault_streak);
  Checks checks{loop::SampleCheck(limits.samples), loop::SampleCheck(limits.samples),
                loop::SampleCheck(limits.samples)};
  const std::size_t n = std::min(force.size(), rec.position.size());
  for (std::size_t k = 0; k < n; ++k) {
    telemetry::TickRecord timing;
    const std::int64_t wake = schedule.wait(k, timing);
    if (stop.load(std::memory_order_relaxed)) {
      rec.end = ExcitationEnd::kStopped;
      break;
    }
    if (!tick(device, force[k], k, wake, schedule.periods(), limits, checks, rec)) break;
    rec.ticks = k + 1;
    std::int64_t compute_ns = 0;
    if (ended_by(schedule.judge(k, wake, timing, compute_ns), rec)) break;
    const std::int64_t skipped = schedule.advance();
    for (loop::SampleCheck& c : checks) c.skipped(skipped);
  }
  const std::array<double, base::kMaxJoints> zero{};
  device.write(std::span<const double>(zero.data(), device.info().joints));
  device.disable();
}

}  // namespace hapticd::service
