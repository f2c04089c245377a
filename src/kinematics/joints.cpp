#include "kinematics/joints.h"

namespace hapticd::kinematics {

Pose joints_forward(const JointsParams& p, const Vec3& q) noexcept {
  Pose pose;
  pose.n = pose.m = p.n;
  pose.x.head(p.n) = q.head(p.n);
  pose.J.topLeftCorner(p.n, p.n).setIdentity();
  pose.status = inside(p.workspace, pose.x, p.n) ? Status::kOk : Status::kOutsideWorkspace;
  return pose;
}

JointSolution joints_inverse(const JointsParams& p, const Vec3& x) noexcept {
  JointSolution s;
  s.n = p.n;
  if (!inside(p.workspace, x, p.n)) {
    s.status = Status::kOutsideWorkspace;
    return s;
  }
  s.q.head(p.n) = x.head(p.n);
  return s;
}

}  // namespace hapticd::kinematics
