#include "control/direction_probe.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "analysis/free_motion_fit.h"

namespace hapticd::control {
namespace {

// Below this many ticks a half of the pulse is too coarse a shape to fit three parameters to.
constexpr int kMinHalfTicks = 3;
// The share of the pulse's motion the device may drift over the rest window and still be at
// rest: the fit removes a steady drift, but not a hand that is moving it.
constexpr double kRestShare = 0.25;
// A gain within this many standard errors of zero is no motion, however large.
constexpr double kSignificance = 4.0;

std::array<double, 9> gram_inverse(const std::vector<double>& e) {
  Eigen::Matrix3d g = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < e.size(); ++i) {
    const Eigen::Vector3d r(1.0, static_cast<double>(i), e[i]);
    g += r * r.transpose();
  }
  const Eigen::Matrix3d inv = g.inverse();
  std::array<double, 9> out{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out[static_cast<std::size_t>(3 * r + c)] = inv(r, c);
  }
  return out;
}

}  // namespace

const char* probe_state_name(ProbeState s) noexcept {
  switch (s) {
    case ProbeState::kOff:
      return "off";
    case ProbeState::kWaiting:
      return "waiting";
    case ProbeState::kPulsing:
      return "pulsing";
    case ProbeState::kConfirmed:
      return "confirmed";
    case ProbeState::kReversed:
      return "reversed";
    case ProbeState::kNoMotion:
      return "no motion";
    case ProbeState::kNeverAtRest:
      return "never at rest";
  }
  return "unknown";
}

double ProbePlan::force_at(int j) const noexcept {
  if (j < half_ticks) return force;
  if (j < 2 * half_ticks) return -brake * force;
  return 0.0;
}

ProbePlan probe_plan(const config::Config& cfg, int device_delay) {
  const config::DirectionCheckConfig& dc = cfg.safety.direction_check;
  ProbePlan p;
  p.enabled = dc.mode == config::DirectionCheckMode::kEnforce;
  const double period = cfg.loop.sample_period_s();
  p.half_ticks =
      std::max(kMinHalfTicks, static_cast<int>(std::ceil(dc.duration_ms * 1e-3 / period - 1e-9)));
  p.rest_ticks = 2 * p.half_ticks;
  p.delay = device_delay;
  // The rest window itself is always waited, however short the time-out.
  p.max_wait_ticks =
      std::max(static_cast<std::uint64_t>(p.rest_ticks),
               static_cast<std::uint64_t>(std::ceil(dc.rest_timeout_ms * 1e-3 / period)));
  p.min_gain = dc.min_motion;
  // Out of the wall first: the way the wall itself would push.
  p.force = -static_cast<double>(cfg.wall.normal) * dc.level * cfg.device.max_force;
  p.brake = std::exp(-p.half_ticks * period * cfg.device.damping / cfg.device.mass);
  // The force acting over each period after the pulse began: the command d ticks late.
  const int after = 3 * p.half_ticks + p.delay;
  std::vector<double> acting(static_cast<std::size_t>(after) + 1, 0.0);
  for (int j = 0; j < 2 * p.half_ticks; ++j) {
    acting[static_cast<std::size_t>(j + p.delay)] = p.force_at(j);
  }
  const std::vector<double> x =
      analysis::free_motion_response(acting, cfg.device.mass, cfg.device.damping, period);
  // The window: R positions of the rest window (the last one where the pulse begins), then
  // the `after` positions that follow it.
  p.expected.assign(static_cast<std::size_t>(p.rest_ticks - 1), 0.0);
  p.expected.insert(p.expected.end(), x.begin(), x.end());
  // The fit: the rest window and the push's own response, up to where the brake begins to act
  // (n + d after the pulse began). From rest, any passive device's step response has the
  // force's sign (a spring holding it only slows it later): the brake's is a spring's business.
  p.fitted = static_cast<std::size_t>(p.rest_ticks + p.half_ticks + p.delay);
  for (const double e : x) {
    if (std::abs(e) > std::abs(p.expected_peak)) p.expected_peak = e;
  }
  if (!(std::abs(p.expected_peak) > 0.0) || !std::isfinite(p.expected_peak)) {
    throw std::invalid_argument(
        "safety.direction_check: the configured mass and damping predict no motion under the "
        "pulse");
  }
  p.rest_tolerance = kRestShare * std::abs(p.expected_peak);
  p.gram_inverse =
      gram_inverse({p.expected.begin(), p.expected.begin() + static_cast<long>(p.fitted)});
  return p;
}

DirectionProbe::DirectionProbe(ProbePlan plan)
    : plan_(std::move(plan)),
      rest_(static_cast<std::size_t>(plan_.rest_ticks), 0.0),
      window_(plan_.window(), 0.0) {
  restart();
}

void DirectionProbe::restart() noexcept {
  rest_head_ = 0;
  rest_count_ = 0;
  pulse_tick_ = 0;
  result_ = {};
  result_.state = plan_.enabled ? ProbeState::kWaiting : ProbeState::kOff;
  result_.force = plan_.force;
  result_.expected_peak = plan_.expected_peak;
}

// RT-safe. Zero force until the last R positions are still; then the pulse's first tick.
double DirectionProbe::wait(double position) noexcept {
  rest_[rest_head_] = position;
  rest_head_ = (rest_head_ + 1) % rest_.size();
  rest_count_ = std::min(rest_count_ + 1, rest_.size());
  if (rest_count_ == rest_.size()) {
    const auto [lo, hi] = std::minmax_element(rest_.begin(), rest_.end());
    if (*hi - *lo <= plan_.rest_tolerance) {
      // Oldest first: the ring's head is the oldest once it is full.
      for (std::size_t i = 0; i < rest_.size(); ++i) {
        window_[i] = rest_[(rest_head_ + i) % rest_.size()];
      }
      result_.state = ProbeState::kPulsing;
      pulse_tick_ = 0;
      return plan_.force_at(0);
    }
  }
  if (result_.ticks >= plan_.max_wait_ticks) result_.state = ProbeState::kNeverAtRest;
  return 0.0;
}

double DirectionProbe::step(double position, std::uint32_t periods) noexcept {
  if (ended()) return 0.0;
  ++result_.ticks;
  if (result_.state == ProbeState::kPulsing && periods != 1) {
    result_.state = ProbeState::kWaiting;  // the force was held longer than the model's
    rest_count_ = 0;
  }
  if (result_.state == ProbeState::kWaiting) return wait(position);
  ++pulse_tick_;
  window_[rest_.size() - 1 + static_cast<std::size_t>(pulse_tick_)] = position;
  if (rest_.size() - 1 + static_cast<std::size_t>(pulse_tick_) + 1 == window_.size()) {
    decide();
    return 0.0;
  }
  return plan_.force_at(pulse_tick_);
}

// RT-safe. The least-squares fit of y_i = a + c i + g e_i and the verdict from g.
void DirectionProbe::decide() noexcept {
  const std::vector<double>& e = plan_.expected;
  const std::array<double, 9>& gi = plan_.gram_inverse;
  const double y0 = window_[0];  // positions relative to the first: no large offsets summed
  double b[3] = {0.0, 0.0, 0.0};
  const std::size_t n = plan_.fitted;
  for (std::size_t i = 0; i < n; ++i) {
    const double y = window_[i] - y0;
    b[0] += y;
    b[1] += static_cast<double>(i) * y;
    b[2] += e[i] * y;
  }
  double theta[3];
  for (int r = 0; r < 3; ++r) {
    theta[r] = gi[3 * r] * b[0] + gi[3 * r + 1] * b[1] + gi[3 * r + 2] * b[2];
  }
  double rss = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double fit = theta[0] + theta[1] * static_cast<double>(i) + theta[2] * e[i];
    const double r = window_[i] - y0 - fit;
    rss += r * r;
  }
  const double dof = static_cast<double>(n) - 3.0;
  result_.gain = theta[2];
  result_.gain_error = std::sqrt(std::max(0.0, rss / dof * gi[8]));
  const double g = result_.gain, clear = kSignificance * result_.gain_error;
  if (!std::isfinite(g)) {
    result_.state = ProbeState::kNoMotion;
  } else if (g >= plan_.min_gain && g > clear) {
    result_.state = ProbeState::kConfirmed;
  } else if (g <= -plan_.min_gain && -g > clear) {
    result_.state = ProbeState::kReversed;
  } else {
    result_.state = ProbeState::kNoMotion;
  }
}

}  // namespace hapticd::control
