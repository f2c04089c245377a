// N independent axes, each its own task coordinate: x = q, J = I. Today's one-axis device is
// this kind with n = 1, and it costs a copy and a box check.
#pragma once

#include "kinematics/pose.h"

namespace hapticd::kinematics {

struct JointsParams {
  int n = 1;      // 1..3
  Box workspace;  // joint ranges, in the joints' own units (unbounded by default)
};

// RT-safe: called every tick.
Pose joints_forward(const JointsParams& p, const Vec3& q) noexcept;

// RT-safe: called every tick.
JointSolution joints_inverse(const JointsParams& p, const Vec3& x) noexcept;

}  // namespace hapticd::kinematics
