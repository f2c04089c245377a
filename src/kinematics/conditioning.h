// How far a square Jacobian is from a singularity, and the Jacobian of a mechanism given
// implicitly by one closure constraint per joint, G(x, q) = 0, each G_i a function of x and
// q_i alone (the pantograph's two legs, the delta's three arms).
#pragma once

#include "kinematics/pose.h"

namespace hapticd::kinematics {

// The largest and smallest singular value of a square n x n Jacobian (m per joint unit): the
// most and the least the effector moves per unit of joint motion, over directions.
struct SingularValues {
  double largest = 0.0;
  double smallest = 0.0;
};

// RT-safe: called every tick. Both 0 for a non-finite J.
SingularValues singular_values(const Mat3& J, int n) noexcept;

// RT-safe: called every tick. sigma_min / sigma_max, in [0, 1]: 1 for an isotropic J, towards 0
// where J loses rank in one direction (a leg folding or stretching straight) or grows without
// bound in one (the mechanism gaining a freedom). Scale-free, so one threshold serves every
// size of device.
double inverse_condition(const Mat3& J, int n) noexcept;

// RT-safe: called every tick. J = dx/dq = -(dG/dx)^-1 diag(dG/dq) for n = m = 2 or 3, from the
// rows of dG/dx and the diagonal of dG/dq. False (J zero) where dG/dx is singular: the
// determinant relative to the product of its row norms (the volume its rows span against the
// largest they could) is under 1e-12, a forward singularity.
bool implicit_jacobian(const Mat3& dg_dx, const Vec3& dg_dq, int n, Mat3& J) noexcept;

// What makes a pose near a singularity: either of two thresholds on J's singular values. The
// ratio catches a J that degenerates in one direction; the smallest value catches one that
// shrinks in every direction at once, which the ratio cannot see (the delta on its axis at full
// reach, all three arms stretched straight together).
struct SingularityThresholds {
  double min_inverse_condition = 0.0;  // sigma_min / sigma_max below it: near a singularity
  double min_singular_value = 0.0;     // sigma_min below it (m per joint unit): near one too
};

// RT-safe: called every tick. The status of a pose whose x and J (when jacobian_ok) are known:
// kOutsideWorkspace outside the box, then kNearSingularity when J is singular or crosses a
// threshold, else kOk.
Status judge(const Box& box, const Vec3& x, int m, const Mat3& J, bool jacobian_ok,
             const SingularityThresholds& near) noexcept;

}  // namespace hapticd::kinematics
