#include "kinematics/cartesian.h"

namespace hapticd::kinematics {

Pose cartesian_forward(const CartesianParams& p, const Vec3& q) noexcept {
  Pose pose;
  pose.n = pose.m = p.n;
  const Vec3 gain = p.sign.cwiseProduct(p.scale);
  pose.x.head(p.n) = gain.head(p.n).cwiseProduct(q.head(p.n));
  pose.J.topLeftCorner(p.n, p.n) = gain.head(p.n).asDiagonal();
  pose.status = inside(p.workspace, pose.x, p.n) ? Status::kOk : Status::kOutsideWorkspace;
  return pose;
}

JointSolution cartesian_inverse(const CartesianParams& p, const Vec3& x) noexcept {
  JointSolution s;
  s.n = p.n;
  if (!inside(p.workspace, x, p.n)) {
    s.status = Status::kOutsideWorkspace;
    return s;
  }
  s.q.head(p.n) = x.head(p.n).cwiseQuotient(p.sign.head(p.n).cwiseProduct(p.scale.head(p.n)));
  return s;
}

}  // namespace hapticd::kinematics
