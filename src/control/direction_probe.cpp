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
// A hand's acceleration over the rest window, carried on over the push's horizon, may move the
// device by at most this share of the push's own motion.
constexpr double kCurvatureShare = 0.1;
// Motion beyond this many times what the model predicts is not the push's. A link that delivers
// the zero after the push late lengthens the push (over an emulated USB controller a 30 ms push
// acted for up to 120 ms: 3.7 to 4 times the model's motion on a free wheel), so the bound
// leaves room for that.
constexpr double kMaxGain = 10.0;
// A push held past this many times its length by a skip is given up: the model still has it,
// but the device has moved far more than the check meant to move it.
constexpr int kMaxPushStretch = 2;

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

double ProbePlan::expected(int c, std::size_t i, int push) const noexcept {
  // Index R - 1 is where the pulse began; the response shows c periods after that. The push
  // is the force held from 0 less the same force held from `push` on.
  const long j = static_cast<long>(i) - (rest_ticks - 1) - c;
  if (j <= 0) return 0.0;
  const double held = step_response[static_cast<std::size_t>(j)];
  return j > push ? held - step_response[static_cast<std::size_t>(j - push)] : held;
}

double ProbePlan::brake_after(int push, int start) const noexcept {
  // The exact ZOH speed of a mass and damper pushed from rest for `push` periods is
  // (F/b)(1 - e^-a push), a = decay; it decays until `start`, and a brake of -s F over n
  // periods takes s (F/b)(1 - e^-a n) of what is left of it then.
  const double n = half_ticks;
  return (1.0 - std::exp(-decay * push)) * std::exp(-decay * (start - push + n)) /
         (1.0 - std::exp(-decay * n));
}

namespace {

// The weights of the quadratic term of a least-squares fit of [1, i, i^2] over `rows` points:
// the last row of (X'X)^-1 X'.
std::vector<double> curvature_weights(int rows) {
  Eigen::MatrixXd x(rows, 3);
  for (int i = 0; i < rows; ++i) x.row(i) << 1.0, i, static_cast<double>(i) * i;
  const Eigen::MatrixXd w = (x.transpose() * x).inverse() * x.transpose();
  std::vector<double> out(static_cast<std::size_t>(rows));
  for (int i = 0; i < rows; ++i) out[static_cast<std::size_t>(i)] = w(2, i);
  return out;
}

// The fitted positions for a response c periods late to a push of `push` periods: the rest
// window and the push's own response, up to where the push's end begins to act (push + c after
// the pulse began), within the window. From rest, any passive device's response to a push has
// the force's sign while it is pushed (a spring holding it only slows it): what follows
// depends on the hand.
std::size_t fitted_rows(const ProbePlan& p, int c, int push) {
  return std::min(p.window(), static_cast<std::size_t>(p.rest_ticks + push + c));
}

}  // namespace

ProbePlan probe_plan(const config::Config& cfg, int device_delay) {
  const config::DirectionCheckConfig& dc = cfg.safety.direction_check;
  ProbePlan p;
  p.enabled = dc.mode == config::DirectionCheckMode::kEnforce;
  const double period = cfg.loop.sample_period_s();
  p.half_ticks =
      std::max(kMinHalfTicks, static_cast<int>(std::ceil(dc.duration_ms * 1e-3 / period - 1e-9)));
  p.rest_ticks = 2 * p.half_ticks;
  p.delay = device_delay;
  p.max_delay =
      device_delay + static_cast<int>(std::ceil(dc.max_latency_ms * 1e-3 / period - 1e-9));
  // The rest window itself is always waited, however short the time-out.
  p.max_wait_ticks =
      std::max(static_cast<std::uint64_t>(p.rest_ticks),
               static_cast<std::uint64_t>(std::ceil(dc.rest_timeout_ms * 1e-3 / period)));
  p.min_gain = dc.min_motion;
  // Out of the wall first: the way the wall itself would push.
  p.force = -static_cast<double>(cfg.wall.normal) * dc.level * cfg.device.max_force[0];
  p.decay = period * cfg.device.damping[0] / cfg.device.mass[0];
  p.brake = p.brake_after(p.half_ticks, p.half_ticks + p.max_delay);
  const std::vector<double> held(static_cast<std::size_t>(p.half_ticks + p.max_delay) + 1, p.force);
  p.step_response =
      analysis::free_motion_response(held, cfg.device.mass[0], cfg.device.damping[0], period);
  for (std::size_t i = 0; i < p.window(); ++i) {
    const double e = p.expected(0, i, p.half_ticks);
    if (std::abs(e) > std::abs(p.expected_peak)) p.expected_peak = e;
  }
  if (!(std::abs(p.expected_peak) > 0.0) || !std::isfinite(p.expected_peak)) {
    throw std::invalid_argument(
        "safety.direction_check: the configured mass and damping predict no motion under the "
        "pulse");
  }
  p.rest_tolerance = kRestShare * std::abs(p.expected_peak);
  p.curvature_weights = curvature_weights(p.rest_ticks);
  const double horizon = p.half_ticks + p.max_delay;
  p.curvature_tolerance = kCurvatureShare * std::abs(p.expected_peak) / (horizon * horizon);
  return p;
}

DirectionProbe::DirectionProbe(ProbePlan plan)
    : plan_(std::move(plan)),
      rest_(static_cast<std::size_t>(plan_.rest_ticks), 0.0),
      window_(plan_.window(), 0.0),
      residual_(plan_.window(), 0.0),
      present_(plan_.window(), 0) {
  restart();
}

void DirectionProbe::restart() noexcept {
  rest_head_ = 0;
  rest_count_ = 0;
  pulse_period_ = 0;
  push_ = 0;
  braking_ = 0;
  result_ = {};
  result_.state = plan_.enabled ? ProbeState::kWaiting : ProbeState::kOff;
  result_.force = plan_.force;
  result_.expected_peak = plan_.expected_peak;
}

// RT-safe. Whether the full rest ring is still: spread, and the acceleration a hand gives it.
bool DirectionProbe::at_rest() const noexcept {
  const auto [lo, hi] = std::minmax_element(rest_.begin(), rest_.end());
  if (!(*hi - *lo <= plan_.rest_tolerance)) return false;
  double q = 0.0;  // oldest first: the ring's head is the oldest once it is full
  for (std::size_t i = 0; i < rest_.size(); ++i) {
    q += plan_.curvature_weights[i] * (rest_[(rest_head_ + i) % rest_.size()] - *lo);
  }
  return std::abs(q) <= plan_.curvature_tolerance;
}

// RT-safe. Zero force until the last R positions are still; then the pulse's first tick.
double DirectionProbe::wait(double position) noexcept {
  rest_[rest_head_] = position;
  rest_head_ = (rest_head_ + 1) % rest_.size();
  rest_count_ = std::min(rest_count_ + 1, rest_.size());
  if (rest_count_ == rest_.size() && at_rest()) {
    // Oldest first: the ring's head is the oldest once it is full.
    for (std::size_t i = 0; i < rest_.size(); ++i) {
      window_[i] = rest_[(rest_head_ + i) % rest_.size()];
    }
    std::fill(present_.begin(), present_.end(), std::uint8_t{0});
    std::fill(present_.begin(), present_.begin() + static_cast<long>(rest_.size()), 1);
    result_.state = ProbeState::kPulsing;
    pulse_period_ = 0;
    push_ = plan_.half_ticks;
    return plan_.force_at(0);
  }
  if (result_.ticks >= plan_.max_wait_ticks) result_.state = ProbeState::kNeverAtRest;
  return 0.0;
}

double DirectionProbe::step(double position, std::uint32_t periods) noexcept {
  if (ended()) return 0.0;
  ++result_.ticks;
  if (braking_ > 0) {  // confirmed: the force's sign is known, so this slows the device
    // The skipped periods held the brake too: what is left of it, this period on.
    const long left = braking_ - (static_cast<long>(periods) - 1);
    braking_ = left > 0 ? static_cast<int>(left) - 1 : 0;
    return left > 0 ? -brake_ * plan_.force : 0.0;
  }
  if (result_.state == ProbeState::kWaiting) return wait(position);
  return pulse(position, std::max<std::uint32_t>(periods, 1));
}

double DirectionProbe::start_over() noexcept {
  result_.state =
      result_.ticks >= plan_.max_wait_ticks ? ProbeState::kNeverAtRest : ProbeState::kWaiting;
  rest_count_ = 0;
  return 0.0;
}

// RT-safe.
double DirectionProbe::pulse(double position, std::uint32_t periods) noexcept {
  const int before = pulse_period_;
  pulse_period_ += static_cast<int>(std::min<std::uint32_t>(periods, 1u << 20));
  // The push's force stayed on over the periods skipped at its end: it ended only now.
  if (before < plan_.half_ticks && pulse_period_ > plan_.half_ticks) push_ = pulse_period_;
  if (push_ > kMaxPushStretch * plan_.half_ticks) return start_over();
  const std::size_t at = rest_.size() - 1 + static_cast<std::size_t>(pulse_period_);
  if (at < window_.size()) {
    window_[at] = position;
    present_[at] = 1;
  }
  if (at + 1 < window_.size()) return plan_.force_at(pulse_period_);
  // Skips left too few positions of the push's own response to fit: another push.
  const std::size_t rows = fitted_rows(plan_, plan_.delay, push_);
  const long read = std::count(present_.begin() + static_cast<long>(rest_.size()),
                               present_.begin() + static_cast<long>(rows), std::uint8_t{1});
  if (2 * read < static_cast<long>(rows - rest_.size()) || read < 3) return start_over();
  decide();
  if ((result_.state == ProbeState::kConfirmed || result_.state == ProbeState::kReversed) &&
      std::abs(result_.gain) > kMaxGain) {
    return start_over();  // far more motion than the push makes: something else moved it
  }
  if (result_.state != ProbeState::kConfirmed) return 0.0;
  brake_ = plan_.brake_after(push_, pulse_period_);
  braking_ = plan_.half_ticks - 1;
  return -brake_ * plan_.force;
}

// RT-safe. The least-squares fit of r_i = g e_c(i) over the push's fitted rows, r the positions
// less the rest window's line: {g, its standard error}. The baseline comes from the rest window
// alone: fitted jointly with the push, a line could take up the response itself (a coarse or
// slow encoder's steps), and the fit at a later delay would see the opposite sign.
std::array<double, 2> DirectionProbe::fit(int c) const noexcept {
  const std::size_t rows = fitted_rows(plan_, c, push_);
  double ee = 0.0, er = 0.0, rr = 0.0;
  int used = 0;
  for (std::size_t i = rest_.size(); i < rows; ++i) {
    if (present_[i] == 0) continue;  // a skipped period: no position
    const double e = plan_.expected(c, i, push_);
    ee += e * e;
    er += e * residual_[i];
    rr += residual_[i] * residual_[i];
    ++used;
  }
  if (!(ee > 0.0) || used < 2) return {0.0, 0.0};
  const double g = er / ee;
  const double dof = static_cast<double>(used) - 1.0;
  return {g, std::sqrt(std::max(0.0, rr - g * er) / dof / ee)};
}

// RT-safe. The fit at each delay the plan allows, from the declared one up: the first that
// shows significant motion of at least min_gain fixes its sign (a shorter delay than the device's
// own still sees the start of the push, whose sign is the force's; a longer one would fit the brake
// and what a hand's spring does after it, whose sign is not). Of the longer delays with a fit of
// that sign, the best one's is the latency, and its gain the motion measured.
void DirectionProbe::decide() noexcept {
  // The rest window's least-squares line, relative to its first position (no large offsets
  // summed), carried on through the push.
  const double y0 = window_[0];
  const double n = static_cast<double>(rest_.size());
  double si = 0.0, sy = 0.0, sii = 0.0, siy = 0.0;
  for (std::size_t i = 0; i < rest_.size(); ++i) {
    const double x = static_cast<double>(i), y = window_[i] - y0;
    si += x;
    sy += y;
    sii += x * x;
    siy += x * y;
  }
  const double slope = (n * siy - si * sy) / (n * sii - si * si);
  const double intercept = (sy - slope * si) / n;
  for (std::size_t i = 0; i < window_.size(); ++i) {
    residual_[i] = window_[i] - y0 - (intercept + slope * static_cast<double>(i));
  }
  const auto t_of = [](const std::array<double, 2>& f) {
    return f[1] > 0.0 ? std::abs(f[0]) / f[1] : (f[0] != 0.0 ? HUGE_VAL : 0.0);
  };
  int c = plan_.delay;
  std::array<double, 2> best = fit(c);
  int found = -1;
  for (; c <= plan_.max_delay; ++c) {
    const std::array<double, 2> f = fit(c);
    // Motion, not a count of drift: significant and as large as the check asks for (a still
    // device's residuals are exact zeros, so one count of creep is significant).
    if (std::isfinite(f[0]) && t_of(f) > kSignificance && std::abs(f[0]) >= plan_.min_gain) {
      best = f;
      found = c;
      break;
    }
    if (t_of(f) > t_of(best)) best = f;  // reported when nothing is significant
  }
  for (int later = found + 1; found >= 0 && later <= plan_.max_delay; ++later) {
    const std::array<double, 2> f = fit(later);
    if (f[0] * best[0] > 0.0 && t_of(f) > t_of(best)) {
      best = f;
      found = later;
    }
  }
  result_.gain = best[0];
  result_.gain_error = best[1];
  result_.latency = found >= 0 ? found - plan_.delay : 0;
  result_.state = found < 0 || !(std::abs(best[0]) >= plan_.min_gain)
                      ? ProbeState::kNoMotion
                      : (best[0] > 0.0 ? ProbeState::kConfirmed : ProbeState::kReversed);
}

}  // namespace hapticd::control
