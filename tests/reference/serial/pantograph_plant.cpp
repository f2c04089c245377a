#include "pantograph_plant.h"

#include <cmath>
#include <stdexcept>

namespace hapticd::reference {
namespace {

// Distal links within about 3 degrees of one line (|sin| of their angle below this) are taken as
// the singular pose, where the mechanism would lock.
constexpr double kSingular = 0.05;

double hypot2(Vec2 v) { return std::hypot(v.x, v.y); }

}  // namespace

PantographPlant::PantographPlant(std::array<JointMechanics, 2> joints, std::array<double, 2> angles,
                                 PantographGeometry geometry)
    : g_(geometry), joints_(joints), theta_(angles) {
  const auto pose = forward(g_, theta_);
  if (!pose) throw std::invalid_argument("pantograph: start angles out of reach");
  pose_ = *pose;
}

std::optional<PantographPose> PantographPlant::forward(const PantographGeometry& g,
                                                       std::array<double, 2> th) {
  const Vec2 a{g.l * std::cos(th[0]), g.l * std::sin(th[0])};
  const Vec2 b{g.d + g.l * std::cos(th[1]), g.l * std::sin(th[1])};
  const Vec2 ab{b.x - a.x, b.y - a.y};
  const double half = hypot2(ab) / 2.0;
  if (half <= 0.0 || half >= g.L) return std::nullopt;
  // Equal radii: E is on the perpendicular bisector of AB, h from its midpoint; of the two, the
  // one of greater y (Pantograph.cpp's + root).
  const double h = std::sqrt(g.L * g.L - half * half);
  Vec2 n{-ab.y / (2.0 * half), ab.x / (2.0 * half)};
  if (n.y < 0.0 || (n.y == 0.0 && n.x < 0.0)) n = {-n.x, -n.y};
  PantographPose p;
  p.effector = {a.x + ab.x / 2.0 + h * n.x, a.y + ab.y / 2.0 + h * n.y};
  // (E-A).(dE - dA) = 0 and (E-B).(dE - dB) = 0, dA = l(-s1, c1) dtheta1, dB = l(-s2, c2)
  // dtheta2: G dE = diag(ka, kb) dtheta with G's rows E-A and E-B.
  const Vec2 ea{p.effector.x - a.x, p.effector.y - a.y};
  const Vec2 eb{p.effector.x - b.x, p.effector.y - b.y};
  const double det = ea.x * eb.y - ea.y * eb.x;
  if (std::abs(det) < kSingular * g.L * g.L) return std::nullopt;
  const double ka = g.l * (-ea.x * std::sin(th[0]) + ea.y * std::cos(th[0]));
  const double kb = g.l * (-eb.x * std::sin(th[1]) + eb.y * std::cos(th[1]));
  // G^-1 = [[eb.y, -ea.y], [-eb.x, ea.x]] / det
  p.jv[0] = {eb.y * ka / det, -ea.y * kb / det};
  p.jv[1] = {-eb.x * ka / det, ea.x * kb / det};
  return p;
}

std::optional<std::array<double, 2>> PantographPlant::inverse(const PantographGeometry& g, Vec2 e) {
  const double r1 = std::hypot(e.x, e.y), r2 = std::hypot(e.x - g.d, e.y);
  const double c1 = (r1 * r1 + g.l * g.l - g.L * g.L) / (2.0 * g.l * r1);
  const double c2 = (r2 * r2 + g.l * g.l - g.L * g.L) / (2.0 * g.l * r2);
  if (!(std::abs(c1) <= 1.0 && std::abs(c2) <= 1.0)) return std::nullopt;
  return std::array<double, 2>{std::atan2(e.y, e.x) + std::acos(c1),
                               std::atan2(e.y, e.x - g.d) - std::acos(c2)};
}

void PantographPlant::step(double dt, std::array<double, 2> motor) {
  const std::lock_guard lock(m_);
  const auto& j = pose_.jv;
  const double c = hand_damping_;
  // (I + dt (B + c Jv^T Jv)) omega' = I omega + dt (tau + Jv^T push)
  const double jtj00 = j[0][0] * j[0][0] + j[1][0] * j[1][0];
  const double jtj01 = j[0][0] * j[0][1] + j[1][0] * j[1][1];
  const double jtj11 = j[0][1] * j[0][1] + j[1][1] * j[1][1];
  const double m00 = joints_[0].inertia + dt * (joints_[0].damping + c * jtj00);
  const double m11 = joints_[1].inertia + dt * (joints_[1].damping + c * jtj11);
  const double m01 = dt * c * jtj01;
  const double r0 =
      joints_[0].inertia * omega_[0] + dt * (motor[0] + j[0][0] * push_.x + j[1][0] * push_.y);
  const double r1 =
      joints_[1].inertia * omega_[1] + dt * (motor[1] + j[0][1] * push_.x + j[1][1] * push_.y);
  const double det = m00 * m11 - m01 * m01;
  const std::array<double, 2> w = {(m11 * r0 - m01 * r1) / det, (m00 * r1 - m01 * r0) / det};
  const std::array<double, 2> next = {theta_[0] + dt * w[0], theta_[1] + dt * w[1]};
  motor_ = motor;
  if (const auto pose = forward(g_, next)) {
    theta_ = next;
    omega_ = w;
    pose_ = *pose;
  } else {
    omega_ = {0.0, 0.0};
    ++locked_;
  }
}

void PantographPlant::hand(Vec2 push_N, double damping) {
  const std::lock_guard lock(m_);
  push_ = push_N;
  hand_damping_ = damping;
}

std::array<double, 2> PantographPlant::angles() const {
  const std::lock_guard lock(m_);
  return theta_;
}

std::array<double, 2> PantographPlant::velocities() const {
  const std::lock_guard lock(m_);
  return omega_;
}

Vec2 PantographPlant::effector() const {
  const std::lock_guard lock(m_);
  return pose_.effector;
}

Vec2 PantographPlant::effector_velocity() const {
  const std::lock_guard lock(m_);
  const auto& j = pose_.jv;
  return {j[0][0] * omega_[0] + j[0][1] * omega_[1], j[1][0] * omega_[0] + j[1][1] * omega_[1]};
}

std::array<double, 2> PantographPlant::motor() const {
  const std::lock_guard lock(m_);
  return motor_;
}

std::uint64_t PantographPlant::locked_steps() const {
  const std::lock_guard lock(m_);
  return locked_;
}

}  // namespace hapticd::reference
