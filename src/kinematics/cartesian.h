// A gantry: each joint drives one task axis, x_i = sign_i * scale_i * q_i, so J is diagonal and
// constant (a gantry has no singularity). `scale` is metres per joint unit (m/rad for a rotary
// motor on a belt or screw, 1 for a linear joint already in metres); `sign` (+1 or -1) says
// which way a positive joint motion moves the axis.
#pragma once

#include "kinematics/pose.h"

namespace hapticd::kinematics {

struct CartesianParams {
  int n = 3;                  // joints = task axes, 1..3
  Vec3 scale = Vec3::Ones();  // m per joint unit, > 0
  Vec3 sign = Vec3::Ones();   // +1 or -1 per axis
  Box workspace;              // on x (m); unbounded by default
};

// RT-safe: called every tick.
Pose cartesian_forward(const CartesianParams& p, const Vec3& q) noexcept;

// RT-safe: called every tick. Each of n joints its own task axis, x_i = gain_i q_i, judged
// against `box`: the cartesian kinds and the joints (gain 1) alike.
Pose diagonal_forward(int n, const Vec3& gain, const Box& box, const Vec3& q) noexcept;
JointSolution diagonal_inverse(int n, const Vec3& gain, const Box& box, const Vec3& x) noexcept;

// RT-safe: called every tick.
JointSolution cartesian_inverse(const CartesianParams& p, const Vec3& x) noexcept;

}  // namespace hapticd::kinematics
