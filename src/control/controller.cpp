#include "control/controller.h"

#include <cmath>

namespace hapticd::control {

Controller::Controller(const ControlLaw& law)
    : law_(law), delay_line_(static_cast<std::size_t>(law.delay_samples) + 1, 0.0) {}

void Controller::reset() noexcept {
  xi_.clear();
  force_.clear();
  proxy_.clear();
  penetration_.clear();
  stepped_ = 0;
  for (double& v : delay_line_) v = 0.0;
  delay_head_ = 0;
  have_last_position_ = false;
  armed_ = false;
}

void Controller::continue_from(const Controller& previous) noexcept {
  xi_ = previous.xi_;
  force_ = previous.force_;
  proxy_ = previous.proxy_;
  penetration_ = previous.penetration_;
  stepped_ = previous.stepped_;
  last_position_ = previous.last_position_;
  have_last_position_ = previous.have_last_position_;
  armed_ = previous.armed_;
  // The newest commands of the old delay line, as many as this one holds: f_{k-1}, f_{k-2}...
  const std::size_t n = delay_line_.size(), m = previous.delay_line_.size();
  for (std::size_t age = 0; age < n; ++age) {
    const double v = age < m ? previous.delay_line_[(previous.delay_head_ + m - age) % m] : 0.0;
    delay_line_[(delay_head_ + n - age) % n] = v;
  }
}

ControlOutput Controller::step(double position) noexcept {
  ControlOutput out;
  out.penetration = law_.normal * (position - law_.wall_position);
  out.velocity = have_last_position_ ? (position - last_position_) * law_.inv_sample_period : 0.0;
  last_position_ = position;
  have_last_position_ = true;
  if (!armed_) {
    if (law_.require_outside_start && out.penetration > 0.0) {
      out.flags |= kControlUnarmed;  // every filter stays at rest: nothing to kick
      return out;
    }
    armed_ = true;
  }
  out.force_computed = wall_force(out.penetration, out.flags);
  out.force_commanded = command(delayed(out.force_computed), out.force_computed, out.flags);
  if (running_away(out)) out.flags |= kControlRunaway;
  penetration_.push(out.penetration);
  if (stepped_ < 2 * kRunawayWindow) ++stepped_;
  return out;
}

double Controller::wall_force(double penetration, std::uint32_t& flags) noexcept {
  // C(z)[f]_k = c0 f_k + c_past; the proxy penetration without c0 f_k is q = p - c_past.
  double c_past = 0.0;
  if (law_.has_coupling) {
    const FilterCoefficients& c = law_.coupling;
    for (std::size_t i = 1; i < c.num_taps; ++i) c_past += c.num[i] * force_.at(i - 1);
    for (std::size_t i = 1; i < c.den_taps; ++i) c_past -= c.den[i] * proxy_.at(i - 1);
  }
  const double q = penetration - c_past;

  // E(z)[xi]_k = e0 xi_k + r: r holds everything that depends on past samples only.
  const FilterCoefficients& e = law_.environment;
  double r = 0.0;
  for (std::size_t i = 1; i < e.num_taps; ++i) r += e.num[i] * xi_.at(i - 1);
  for (std::size_t i = 1; i < e.den_taps; ++i) r -= e.den[i] * force_.at(i - 1);

  // The unique solution of f = e0 max(q - c0 f, 0) + r for e0, c0 >= 0.
  double f = r;
  double xi = 0.0;
  if (law_.linear_contact || q - law_.c0 * r > 0.0) {
    f = (r + law_.e0 * q) * law_.inv_one_plus_e0c0;
    xi = q - law_.c0 * f;
    flags |= kControlContact;
  }
  xi_.push(xi);
  force_.push(f);
  proxy_.push(law_.c0 * f + c_past);
  return f;
}

double Controller::delayed(double f) noexcept {
  // Delay line of d + 1 slots: after writing f_k, the slot after it holds f_{k-d}.
  const std::size_t n = delay_line_.size();
  delay_head_ = delay_head_ + 1 == n ? 0 : delay_head_ + 1;
  delay_line_[delay_head_] = f;
  return delay_line_[delay_head_ + 1 == n ? 0 : delay_head_ + 1];
}

bool Controller::running_away(const ControlOutput& out) const noexcept {
  // -n u > 0: the command pushes out of the wall, at its limit, and still the device is deeper
  // than the saturated wall can hold.
  if (!(out.flags & kControlSaturated) || !(out.penetration > law_.runaway_penetration) ||
      !(-law_.normal * out.force_commanded > 0.0) || stepped_ < 2 * kRunawayWindow) {
    return false;
  }
  constexpr std::size_t w = kRunawayWindow;
  const double last = out.penetration - penetration_.at(w - 1);
  const double before = penetration_.at(w - 1) - penetration_.at(2 * w - 1);
  return last >= before;  // not braked: pulled in, pushed through, or held there
}

double Controller::command(double applied, double f, std::uint32_t& flags) const noexcept {
  if (law_.no_pull && applied < 0.0) {
    applied = 0.0;
    flags |= kControlNoPullClamped;
  }
  double u = -law_.normal * applied;
  if (!std::isfinite(f) || !std::isfinite(u)) {
    // Never saturate a NaN into +-max_force: command nothing and let the loop fault.
    u = 0.0;
    flags |= kControlNonFinite;
  } else if (std::abs(u) > law_.max_force) {
    u = std::copysign(law_.max_force, u);
    flags |= kControlSaturated;
  }
  return u;
}

}  // namespace hapticd::control
