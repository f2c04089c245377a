#include "kinematics/cartesian.h"

namespace hapticd::kinematics {

Pose diagonal_forward(int n, const Vec3& gain, const Box& box, const Vec3& q) noexcept {
  Pose pose;
  pose.n = pose.m = n;
  pose.x.head(n) = gain.head(n).cwiseProduct(q.head(n));
  pose.J.topLeftCorner(n, n) = gain.head(n).asDiagonal();
  pose.status = inside(box, pose.x, n) ? Status::kOk : Status::kOutsideWorkspace;
  return pose;
}

JointSolution diagonal_inverse(int n, const Vec3& gain, const Box& box, const Vec3& x) noexcept {
  JointSolution s;
  s.n = n;
  if (!inside(box, x, n)) {
    s.status = Status::kOutsideWorkspace;
    return s;
  }
  s.q.head(n) = x.head(n).cwiseQuotient(gain.head(n));
  return s;
}

Pose cartesian_forward(const CartesianParams& p, const Vec3& q) noexcept {
  return diagonal_forward(p.n, p.sign.cwiseProduct(p.scale), p.workspace, q);
}

JointSolution cartesian_inverse(const CartesianParams& p, const Vec3& x) noexcept {
  return diagonal_inverse(p.n, p.sign.cwiseProduct(p.scale), p.workspace, x);
}

}  // namespace hapticd::kinematics
