#include "control/passivity_observer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hapticd::control {
const char* passivity_mode_name(config::PassivityControl mode) noexcept {
  switch (mode) {
    case config::PassivityControl::kOff:
      return "off";
    case config::PassivityControl::kObserve:
      return "observe";
    case config::PassivityControl::kDamp:
      return "damp";
  }
  return "unknown";
}

ObserverParams observer_params(const config::Config& cfg, int device_delay_samples) {
  ObserverParams p;
  p.mode = cfg.safety.passivity_controller;
  p.device_damping = cfg.device.damping[0];
  p.sample_period = cfg.loop.sample_period_s();
  p.device_delay = device_delay_samples;
  p.max_damping = std::min(cfg.safety.passivity_max_damping,
                           kStableDampingFraction * 2.0 * cfg.device.mass[0] / p.sample_period);
  return p;
}

PassivityObserver::PassivityObserver(const ObserverParams& params) : params_(params) {
  if (params.device_delay < 0) {
    throw std::invalid_argument("the passivity observer needs a device delay >= 0, not " +
                                std::to_string(params.device_delay));
  }
  std::size_t size = 1;
  while (size < static_cast<std::size_t>(params.device_delay) + 1) size *= 2;
  history_.assign(size, 0.0);
  damping_history_.assign(size, 0.0);
  mask_ = size - 1;
  if (!(params.sample_period > 0.0)) {
    throw std::invalid_argument("the passivity observer needs a sample period > 0");
  }
  inv_period_ = 1.0 / params.sample_period;
}

std::size_t PassivityObserver::acting() const noexcept {
  return (head_ - static_cast<std::size_t>(params_.device_delay)) & mask_;
}

void PassivityObserver::observe(double position, bool fresh, std::uint32_t periods) noexcept {
  if (!have_x_) {
    last_x_ = position;
    have_x_ = true;
    return;
  }
  const std::size_t slot = acting();
  const double n_periods = static_cast<double>(periods);
  pending_force_ += history_[slot] * n_periods;
  pending_damping_ += damping_history_[slot] * n_periods;
  pending_periods_ += periods;
  if (!fresh) {
    if (energy_ < 0.0) ++negative_ticks_;
    return;  // the held position: the motion shows in the next sample
  }
  const double dx = position - last_x_;
  // The usual case, one period since the last sample, divides nothing.
  const bool spread = pending_periods_ != 1;
  const double n = static_cast<double>(pending_periods_);
  const double force = spread ? pending_force_ / n : pending_force_;
  wall_work_ += force * dx;
  if (enabled()) {
    const double v = spread ? dx * inv_period_ / n : dx * inv_period_;
    energy_ += params_.device_damping * v * dx - force * dx;
    damping_work_ -= (spread ? pending_damping_ / n : pending_damping_) * dx;
    previous_velocity_ = velocity_;
    velocity_ = v;
    min_energy_ = std::min(min_energy_, energy_);
    if (energy_ < 0.0) ++negative_ticks_;
    if (energy_ < 0.0 && !in_deficit_) deficit_start_work_ = damping_work_;
    in_deficit_ = energy_ < 0.0;
  }
  last_x_ = position;
  pending_force_ = 0.0;
  pending_damping_ = 0.0;
  pending_periods_ = 0;
}

Damping PassivityObserver::damp(double wall, const ControlLaw& law) noexcept {
  Damping out;
  out.command = wall;
  if (params_.mode != config::PassivityControl::kDamp || !(energy_ < 0.0) || velocity_ == 0.0) {
    return out;
  }
  // The governor: in this deficit the controller's forces have put in more than they took out.
  if (damping_work_ < deficit_start_work_) return out;
  // alpha v^2 T = -E: the damping that would dissipate the deficit over one period.
  const double alpha =
      std::min(-energy_ * inv_period_ / (velocity_ * velocity_), params_.max_damping);
  // The force acts over the coming period: against the velocity expected there. A motion
  // that reversed over the last period is taken to reverse again (the sampled loop's
  // oscillation near the Nyquist rate, which a damper on the last velocity would feed).
  const double expected = velocity_ * previous_velocity_ < 0.0 ? -velocity_ : velocity_;
  double u = wall - alpha * expected;
  if (!std::isfinite(u)) return out;  // nothing to add that can be trusted
  if (std::abs(u) > law.max_force) {
    u = std::copysign(law.max_force, u);
    out.saturated = true;
  }
  if (law.no_pull && -law.normal * u < 0.0) u = 0.0;  // the wall's force along n stays >= 0
  if (u == wall) return Damping{wall, 0.0, 0.0, out.saturated};  // nothing was added
  out.command = u;
  out.added = u - wall;
  out.alpha = alpha;
  ++damped_ticks_;
  max_alpha_ = std::max(max_alpha_, alpha);
  return out;
}

void PassivityObserver::commanded(double force, double added) noexcept {
  head_ = (head_ + 1) & mask_;
  history_[head_] = force;
  damping_history_[head_] = added;
}

void PassivityObserver::restart() noexcept {
  std::fill(history_.begin(), history_.end(), 0.0);
  std::fill(damping_history_.begin(), damping_history_.end(), 0.0);
  have_x_ = false;
  pending_force_ = 0.0;
  pending_damping_ = 0.0;
  pending_periods_ = 0;
  velocity_ = 0.0;
  previous_velocity_ = 0.0;
}

void PassivityObserver::continue_from(const PassivityObserver& previous) noexcept {
  // The newest commands of the old history, as many as this one holds (both are sized by the
  // same device's delay; the ages keep them right if they were not).
  const std::size_t n = history_.size(), m = previous.history_.size();
  for (std::size_t age = 0; age < n; ++age) {
    const std::size_t from = (previous.head_ + m - age % m) & previous.mask_;
    const std::size_t to = (head_ + n - age) & mask_;
    history_[to] = age < m ? previous.history_[from] : 0.0;
    damping_history_[to] = age < m ? previous.damping_history_[from] : 0.0;
  }
  last_x_ = previous.last_x_;
  have_x_ = previous.have_x_;
  pending_force_ = previous.pending_force_;
  pending_damping_ = previous.pending_damping_;
  pending_periods_ = previous.pending_periods_;
  velocity_ = previous.velocity_;
  previous_velocity_ = previous.previous_velocity_;
  energy_ = previous.energy_;
  wall_work_ = previous.wall_work_;
  damping_work_ = previous.damping_work_;
  min_energy_ = previous.min_energy_;
  negative_ticks_ = previous.negative_ticks_;
  damped_ticks_ = previous.damped_ticks_;
  max_alpha_ = previous.max_alpha_;
  in_deficit_ = previous.in_deficit_;
  deficit_start_work_ = previous.deficit_start_work_;
}

}  // namespace hapticd::control
