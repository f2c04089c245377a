#include "kinematics/pose.h"

#include <cmath>

namespace hapticd::kinematics {

const char* status_name(Status s) noexcept {
  switch (s) {
    case Status::kOk:
      return "ok";
    case Status::kOutsideWorkspace:
      return "outside workspace";
    case Status::kNearSingularity:
      return "near singularity";
    case Status::kNoConvergence:
      return "no convergence";
  }
  return "unknown";
}

bool inside(const Box& box, const Vec3& x, int m) noexcept {
  for (int i = 0; i < m; ++i) {
    // Written so that NaN compares outside; an infinite coordinate is outside an unbounded box
    // too (a joint's overflow is no position).
    if (!(std::isfinite(x[i]) && x[i] >= box.lower[i] && x[i] <= box.upper[i])) return false;
  }
  return true;
}

Vec3 joint_torques(const Pose& pose, const Vec3& force) noexcept {
  Vec3 f = Vec3::Zero();
  f.head(pose.m) = force.head(pose.m);  // entries past m are no force of this device
  return pose.J.transpose() * f;
}

Vec3 task_velocity(const Pose& pose, const Vec3& joint_velocity) noexcept {
  Vec3 v = Vec3::Zero();
  v.head(pose.n) = joint_velocity.head(pose.n);
  return pose.J * v;
}

}  // namespace hapticd::kinematics
