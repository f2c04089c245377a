#include "sim/plant.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include <unsupported/Eigen/MatrixFunctions>

namespace hapticd::sim {

namespace {

using Kind = config::OperatorSpec::Kind;

// Indices into the augmented state.
constexpr int kX = 0;
constexpr int kV = 1;
constexpr int kS = 2;    // profile value (set-point or force)
constexpr int kSd = 3;   // its time derivative
constexpr int kOne = 4;  // constant 1, carries the sine's offset
constexpr int kU = 5;    // motor force, held for the period

// A breakpoint closer than this to a sample instant is taken to lie on it: t / T rarely lands
// exactly on an integer in floating point, and a split of ~1e-19 s would be pure noise.
constexpr double kOnInstantFraction = 1e-9;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("sim plant: " + message);
}

bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

Plant::Plant(double mass, double damping, const config::OperatorSpec& op, double sample_period_s,
             double x0, double v0, std::vector<double> replay_positions)
    : kind_(op.kind),
      mass_(mass),
      damping_(damping),
      period_(sample_period_s),
      inv_period_(1.0 / sample_period_s),
      motion_(op.motion),
      replay_(std::move(replay_positions)) {
  require(std::isfinite(period_) && period_ > 0.0, "sample period must be finite and > 0");
  require(std::isfinite(mass_) && mass_ > 0.0, "device mass must be finite and > 0");
  require(finite_nonneg(damping_), "device damping must be finite and >= 0");
  require(std::isfinite(x0) && std::isfinite(v0), "initial position and velocity must be finite");
  require(kind_ == Kind::kReplay || replay_.empty(),
          "replay positions were given but the operator is not a replay");

  if (kind_ == Kind::kReplay) {
    require(!replay_.empty(), "replay operator needs at least one position (the log is empty)");
    for (std::size_t i = 0; i < replay_.size(); ++i) {
      require(std::isfinite(replay_[i]), "replay position " + std::to_string(i) + " is not finite");
    }
  } else if (kind_ == Kind::kMotion) {
    require(std::isfinite(motion_.offset) && std::isfinite(motion_.amplitude) &&
                std::isfinite(motion_.frequency_hz) && std::isfinite(motion_.phase_rad),
            "imposed motion parameters must be finite");
  } else {
    Mat a = Mat::Zero();
    a(kX, kV) = 1.0;
    a(kV, kV) = -damping_ / mass_;
    a(kV, kU) = 1.0 / mass_;
    if (kind_ == Kind::kHand) {
      require(finite_nonneg(op.stiffness), "hand stiffness must be finite and >= 0");
      require(finite_nonneg(op.damping), "hand damping must be finite and >= 0");
      hand_stiffness_ = op.stiffness;
      hand_damping_ = op.damping;
      profile_ = Profile(op.setpoint);
      a(kV, kX) = -hand_stiffness_ / mass_;
      a(kV, kV) = -(damping_ + hand_damping_) / mass_;
      a(kV, kS) = hand_stiffness_ / mass_;
    } else if (kind_ == Kind::kForce) {
      profile_ = Profile(op.force);
      a(kV, kS) = 1.0 / mass_;
    }
    a(kS, kSd) = 1.0;
    if (profile_.is_sine()) {
      // s'' = -w^2 (s - offset): the sine is the free response of this generator.
      const double w2 = profile_.sine_omega() * profile_.sine_omega();
      a(kSd, kS) = -w2;
      a(kSd, kOne) = w2 * profile_.sine_offset();
    }
    build_linear(a);
    z0_(kX) = x0;
    z0_(kV) = v0;
    z0_(kOne) = 1.0;
  }
  reset();
}

namespace {

// Exact discretisation over tau: Phi = expm(A tau) and, by Van Loan's method, the Gramian
// V = integral_0^tau expm(A' t) e_v e_v' expm(A t) dt, so that integral of v^2 = z0' V z0.
template <typename Mat>
std::pair<Mat, Mat> discretise(const Mat& a, double tau) {
  constexpr int n = Mat::RowsAtCompileTime;
  Eigen::Matrix<double, 2 * n, 2 * n> c = Eigen::Matrix<double, 2 * n, 2 * n>::Zero();
  c.template topLeftCorner<n, n>() = -a.transpose();
  c(kV, n + kV) = 1.0;  // Q = e_v e_v'
  c.template bottomRightCorner<n, n>() = a;
  const Eigen::Matrix<double, 2 * n, 2 * n> e = (c * tau).exp();
  const Mat phi = (a * tau).exp();  // the small expm alone is a touch more accurate
  Mat v2 = e.template bottomRightCorner<n, n>().transpose() * e.template topRightCorner<n, n>();
  v2 = (0.5 * (v2 + v2.transpose())).eval();
  return {phi, v2};
}

}  // namespace

void Plant::build_linear(const Mat& a) {
  auto [phi, v2] = discretise(a, period_);
  full_ = Discrete{phi, v2};

  // Classify each knot: on a sample instant (the generator is re-anchored there anyway) or
  // strictly inside a period (that step is split at the knot).
  const double tol = kOnInstantFraction * period_;
  constexpr double kFar = 4.0e18;  // beyond any reachable step count
  const auto& knots = profile_.knots();
  knot_instant_.reserve(knots.size());
  double previous_offset = 0.0;
  std::int64_t previous_period = -1;
  for (std::size_t j = 0; j < knots.size(); ++j) {
    const double q = std::floor(knots[j].t_s / period_);
    if (q >= kFar || q <= -kFar) {
      knot_instant_.push_back(q > 0 ? std::numeric_limits<std::int64_t>::max()
                                    : std::numeric_limits<std::int64_t>::min());
      continue;
    }
    const auto k = static_cast<std::int64_t>(q);
    const double c = knots[j].t_s - static_cast<double>(k) * period_;
    if (c <= tol) {
      knot_instant_.push_back(k);
    } else if (period_ - c <= tol) {
      knot_instant_.push_back(k + 1);
    } else {
      knot_instant_.push_back(k + 1);
      if (k < 0) continue;  // already behind t = 0
      const double start = (k == previous_period) ? previous_offset : 0.0;
      auto [lead_phi, lead_v2] = discretise(a, c - start);
      auto [tail_phi, tail_v2] = discretise(a, period_ - c);
      splits_.push_back(Split{k, j, Discrete{lead_phi, lead_v2}, Discrete{tail_phi, tail_v2}});
      previous_period = k;
      previous_offset = c;
    }
  }
}

bool Plant::imposed() const noexcept { return kind_ == Kind::kMotion || kind_ == Kind::kReplay; }

double Plant::imposed_position(std::uint64_t k) const noexcept {
  if (kind_ == Kind::kReplay) return k < replay_.size() ? replay_[k] : replay_.back();
  const double t = static_cast<double>(k) * period_;
  return motion_.offset +
         motion_.amplitude *
             std::cos(2.0 * std::numbers::pi * motion_.frequency_hz * t + motion_.phase_rad);
}

void Plant::reset() noexcept {
  k_ = 0;
  operator_work_ = 0.0;
  dissipated_ = 0.0;
  motor_work_ = 0.0;
  last_motor_force_ = 0.0;
  if (imposed()) {
    // Already moving along the trajectory at t = 0: no impulse at the first instant.
    x_ = imposed_position(0);
    v_ = (imposed_position(1) - x_) * inv_period_;
    return;
  }
  z_ = z0_;
  seg_ = 0;
  next_split_ = 0;
  while (seg_ < knot_instant_.size() && knot_instant_[seg_] <= 0) ++seg_;
  anchor_generator();
  x_ = z_(kX);
  v_ = z_(kV);
}

// Sets the generator to the profile's exact right-limit value and slope at the current
// instant. Mathematically redundant with Phi, it stops round-off drift over long runs and
// applies jumps and slope changes that fall on sample instants.
void Plant::anchor_generator() noexcept {
  const double t = time_s();
  if (profile_.is_sine()) {
    z_(kS) = profile_.value(t);
    z_(kSd) = profile_.slope(t);
  } else {
    const Profile::Segment& s = profile_.segment(seg_);
    z_(kS) = s.value0 + s.slope * (t - s.t0_s);
    z_(kSd) = s.slope;
  }
  z_(kOne) = 1.0;
}

void Plant::advance(const Discrete& d, double& v2_integral) noexcept {
  v2_integral += z_.dot(d.v2 * z_);
  z_ = (d.phi * z_).eval();
}

void Plant::step(double motor_force) noexcept {
  if (imposed()) {
    step_imposed(motor_force);
  } else {
    step_linear(motor_force);
  }
}

void Plant::step_linear(double u) noexcept {
  z_(kU) = u;
  const double x_start = z_(kX);
  const double v_start = z_(kV);
  double v2_integral = 0.0;
  const auto k = static_cast<std::int64_t>(k_);
  if (next_split_ < splits_.size() && splits_[next_split_].period == k) {
    const Split* last = nullptr;
    while (next_split_ < splits_.size() && splits_[next_split_].period == k) {
      last = &splits_[next_split_++];
      advance(last->lead, v2_integral);
      // At the breakpoint: the next segment's value (a jump resets it) and slope.
      seg_ = last->knot + 1;
      const Profile::Segment& s = profile_.segment(seg_);
      z_(kS) = s.value0;
      z_(kSd) = s.slope;
    }
    advance(last->tail, v2_integral);
  } else {
    advance(full_, v2_integral);
  }
  ++k_;
  while (seg_ < knot_instant_.size() && knot_instant_[seg_] <= static_cast<std::int64_t>(k_)) {
    ++seg_;
  }
  anchor_generator();

  x_ = z_(kX);
  v_ = z_(kV);
  const double dissipated = damping_ * v2_integral;
  const double motor = u * (x_ - x_start);  // u is constant over the period
  dissipated_ += dissipated;
  motor_work_ += motor;
  operator_work_ += 0.5 * mass_ * (v_ * v_ - v_start * v_start) + dissipated - motor;
}

void Plant::step_imposed(double u) noexcept {
  const double x_next = imposed_position(k_ + 1);
  const double v_next = (x_next - x_) * inv_period_;
  // The operator's impulse at the instant changes KE by the velocity jump; inside the period
  // the velocity is constant, so v^2 integrates to v^2 T.
  const double dissipated = damping_ * v_next * v_next * period_;
  const double motor = u * (x_next - x_);
  operator_work_ += 0.5 * mass_ * (v_next * v_next - v_ * v_) + dissipated - motor;
  dissipated_ += dissipated;
  motor_work_ += motor;
  last_motor_force_ = u;
  x_ = x_next;
  v_ = v_next;
  ++k_;
}

double Plant::operator_force() const noexcept {
  switch (kind_) {
    case Kind::kHand:
      return hand_stiffness_ * (z_(kS) - x_) - hand_damping_ * v_;
    case Kind::kForce:
      return z_(kS);
    case Kind::kMotion:
    case Kind::kReplay:
      // Zero acceleration inside the period: 0 = -b v + u + f_op.
      return damping_ * v_ - last_motor_force_;
    case Kind::kNone:
      break;
  }
  return 0.0;
}

}  // namespace hapticd::sim
