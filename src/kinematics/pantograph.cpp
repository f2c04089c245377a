#include "kinematics/pantograph.h"

#include <cmath>

#include "kinematics/conditioning.h"

namespace hapticd::kinematics {
namespace {

using Vec2 = Eigen::Vector2d;

Vec2 base(const PantographParams& p, int i) {
  return Vec2((i == 0 ? -0.5 : 0.5) * p.base_separation, 0.0);
}

// The proximal link, base to elbow, and its derivative by q_i.
Vec2 arm(const PantographParams& p, int i, double q) {
  return p.proximal[i] * Vec2(std::cos(q), std::sin(q));
}
Vec2 arm_rate(const PantographParams& p, int i, double q) {
  return p.proximal[i] * Vec2(-std::sin(q), std::cos(q));
}

}  // namespace

Pose pantograph_forward(const PantographParams& p, const Vec3& q) noexcept {
  Pose pose;
  pose.n = pose.m = 2;
  pose.status = Status::kOutsideWorkspace;
  const Vec2 e0 = base(p, 0) + arm(p, 0, q[0]);
  const Vec2 e1 = base(p, 1) + arm(p, 1, q[1]);
  const Vec2 d = e1 - e0;
  const double dist = d.norm();
  const double b0 = p.distal[0], b1 = p.distal[1];
  // Along E_0 -> E_1 to the chord, then across it to the left (the working mode).
  const double along = (b0 * b0 - b1 * b1 + dist * dist) / (2 * dist);
  const double across_sq = b0 * b0 - along * along;
  if (!(dist > 0) || !(across_sq >= 0)) return pose;  // the distal links cannot meet
  const Vec2 u = d / dist;
  const Vec2 x = e0 + along * u + std::sqrt(across_sq) * Vec2(-u.y(), u.x());
  pose.x.head<2>() = x;
  // G_i = |x - E_i|^2 - b_i^2 = 0: dG_i/dx = 2 (x - E_i)^T, dG_i/dq_i = -2 (x - E_i) . E_i'.
  Mat3 dg_dx = Mat3::Zero();
  Vec3 dg_dq = Vec3::Zero();
  const Vec2 r0 = x - e0, r1 = x - e1;
  dg_dx.row(0).head<2>() = 2 * r0.transpose();
  dg_dx.row(1).head<2>() = 2 * r1.transpose();
  dg_dq[0] = -2 * r0.dot(arm_rate(p, 0, q[0]));
  dg_dq[1] = -2 * r1.dot(arm_rate(p, 1, q[1]));
  const bool ok = implicit_jacobian(dg_dx, dg_dq, 2, pose.J);
  pose.status = judge(p.workspace, pose.x, 2, pose.J, ok, p.near);
  return pose;
}

JointSolution pantograph_inverse(const PantographParams& p, const Vec3& x) noexcept {
  JointSolution s;
  s.n = 2;
  s.status = Status::kOutsideWorkspace;
  if (!inside(p.workspace, x, 2)) return s;
  Vec3 q = Vec3::Zero();
  for (int i = 0; i < 2; ++i) {
    const Vec2 r = x.head<2>() - base(p, i);
    const double rho = r.norm();
    const double a = p.proximal[i], b = p.distal[i];
    // The angle at the base between the ray to x and the proximal link (law of cosines).
    const double c = (a * a + rho * rho - b * b) / (2 * a * rho);
    if (!(rho > 0) || !(std::abs(c) <= 1)) return s;  // beyond this leg's reach
    const double gamma = std::acos(c);
    // Elbows out: the left one counter-clockwise of its ray, the right one clockwise.
    q[i] = std::atan2(r.y(), r.x()) + (i == 0 ? gamma : -gamma);
  }
  s.q = q;
  s.status = Status::kOk;
  return s;
}

}  // namespace hapticd::kinematics
