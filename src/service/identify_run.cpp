#include "service/identify_run.h"

#include <cmath>

#include "base/clock.h"
#include "loop/rt_setup.h"

namespace hapticd::service {
namespace {

constexpr int kStaleTicks = 3;  // ticks in a row without a fresh sample that end it

// One tick: read, check, write the planned force. RT-safe: called every tick.
bool tick(Device& device, double force, std::size_t k, double max_travel, int& stale,
          ExcitationRecord& rec) noexcept {
  PositionSample s;
  const IoStatus st = device.read(s);
  if (st == IoStatus::kTransportFault || st == IoStatus::kDeviceFault) {
    rec.end = ExcitationEnd::kDeviceFault;
    return false;
  }
  if (st == IoStatus::kOk && !std::isfinite(s.position)) {
    rec.end = ExcitationEnd::kNonFinite;
    return false;
  }
  rec.valid[k] = st == IoStatus::kOk;
  stale = rec.valid[k] ? 0 : stale + 1;
  if (stale >= kStaleTicks) {
    rec.end = ExcitationEnd::kStale;
    return false;
  }
  rec.position[k] = rec.valid[k] ? s.position : (k > 0 ? rec.position[k - 1] : 0.0);
  if (rec.valid[k] && !rec.started) {
    rec.start = s.position;
    rec.started = true;
  }
  if (rec.started && std::abs(rec.position[k] - rec.start) > max_travel) {
    rec.end = ExcitationEnd::kTravel;
    return false;
  }
  const IoStatus ws = device.write(force);
  if (ws == IoStatus::kTransportFault || ws == IoStatus::kDeviceFault) {
    rec.end = ExcitationEnd::kDeviceFault;
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

void run_excitation(Device& device, std::span<const double> force, double period_s, bool realtime,
                    double max_travel, const std::atomic<bool>& stop,
                    ExcitationRecord& rec) noexcept {
  loop::prefault_stack();
  const auto period = static_cast<std::int64_t>(std::llround(period_s * 1e9));
  std::int64_t deadline = base::monotonic_ns();
  int stale = 0;
  const std::size_t n = std::min(force.size(), rec.position.size());
  for (std::size_t k = 0; k < n; ++k, deadline += period) {
    if (realtime) base::sleep_until_ns(deadline);
    if (stop.load(std::memory_order_relaxed)) {
      rec.end = ExcitationEnd::kStopped;
      break;
    }
    if (!tick(device, force[k], k, max_travel, stale, rec)) break;
    rec.ticks = k + 1;
  }
  device.write(0.0);
  device.disable();
}

}  // namespace hapticd::service
