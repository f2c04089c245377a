#include "reference/can/reference_plant.h"

#include <algorithm>

namespace hapticd::reference {

ReferencePlant::ReferencePlant(const PlantParameters& p, std::int64_t t0_ns)
    : p_(p),
      t_ns_(t0_ns),
      x_(p.start),
      published_x_(p.start),
      hand_start_ns_(t0_ns + static_cast<std::int64_t>(p.hand_start_s * 1e9)),
      hand_force_(p.hand_force) {}

double ReferencePlant::hand(std::int64_t t_ns) const {
  const double since = static_cast<double>(t_ns - hand_start_ns_.load()) * 1e-9;
  return hand_force_.load(std::memory_order_relaxed) * std::clamp(since / p_.hand_ramp_s, 0.0, 1.0);
}

void ReferencePlant::advance_to(std::int64_t t_ns) {
  if (t_ns <= t_ns_) return;
  // A drive thread starved for long is a stalled host, not a moving axis: at most 50 ms.
  if (t_ns - t_ns_ > 50'000'000) t_ns_ = t_ns - 50'000'000;
  const double h = p_.step_s;
  while (t_ns_ < t_ns) {
    const double dt = std::min(h, static_cast<double>(t_ns - t_ns_) * 1e-9);
    const double a = (motor_force_ + hand(t_ns_) - p_.damping * v_) / p_.mass;
    v_ += a * dt;
    x_ += v_ * dt;
    t_ns_ += static_cast<std::int64_t>(dt * 1e9 + 0.5);
  }
  published_x_.store(x_, std::memory_order_relaxed);
  published_f_.store(motor_force_, std::memory_order_relaxed);
}

}  // namespace hapticd::reference
