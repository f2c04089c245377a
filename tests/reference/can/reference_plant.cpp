#include "reference/can/reference_plant.h"

#include <algorithm>

namespace hapticd::reference {

ReferencePlant::ReferencePlant(const PlantParameters& p, std::int64_t t0_ns)
    : p_(p), t0_ns_(t0_ns), t_ns_(t0_ns), x_(p.start), published_x_(p.start) {}

double ReferencePlant::hand(double t_s) const {
  const double ramp = std::clamp((t_s - p_.hand_start_s) / p_.hand_ramp_s, 0.0, 1.0);
  return p_.hand_force * ramp;
}

void ReferencePlant::advance_to(std::int64_t t_ns) {
  if (t_ns <= t_ns_) return;
  // A drive thread starved for long is a stalled host, not a moving axis: at most 50 ms.
  if (t_ns - t_ns_ > 50'000'000) t_ns_ = t_ns - 50'000'000;
  const double h = p_.step_s;
  while (t_ns_ < t_ns) {
    const double dt = std::min(h, static_cast<double>(t_ns - t_ns_) * 1e-9);
    const double t = static_cast<double>(t_ns_ - t0_ns_) * 1e-9;
    const double a = (motor_force_ + hand(t) - p_.damping * v_) / p_.mass;
    v_ += a * dt;
    x_ += v_ * dt;
    t_ns_ += static_cast<std::int64_t>(dt * 1e9 + 0.5);
  }
  published_x_.store(x_, std::memory_order_relaxed);
  published_f_.store(motor_force_, std::memory_order_relaxed);
}

}  // namespace hapticd::reference
