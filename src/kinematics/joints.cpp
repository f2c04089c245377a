#include "kinematics/joints.h"

#include "kinematics/cartesian.h"

namespace hapticd::kinematics {

Pose joints_forward(const JointsParams& p, const Vec3& q) noexcept {
  return diagonal_forward(p.n, Vec3::Ones(), p.workspace, q);
}

JointSolution joints_inverse(const JointsParams& p, const Vec3& x) noexcept {
  return diagonal_inverse(p.n, Vec3::Ones(), p.workspace, x);
}

}  // namespace hapticd::kinematics
