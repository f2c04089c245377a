// How far a square Jacobian is from a singularity, and the Jacobian of a mechanism given
// implicitly by one closure constraint per joint, G(x, q) = 0, each G_i a function of x and
// q_i alone (the pantograph's two legs, the delta's three arms).
#pragma once

#include "kinematics/pose.h"

namespace hapticd::kinematics {

// RT-safe: called every tick. sigma_min / sigma_max of the n x n top-left block of J, in
// [0, 1]: 1 for an isotropic J, 0 at a singularity of either kind (J losing rank where a leg
// folds or stretches straight, J growing without bound where the mechanism gains a freedom).
// Scale-free, so one threshold serves every size of device built with the same units on all
// joints (and on all task axes). 0 for a non-finite J.
double inverse_condition(const Mat3& J, int n) noexcept;

// RT-safe: called every tick. J = dx/dq = -(dG/dx)^-1 diag(dG/dq) for n = m = 2 or 3, from the
// rows of dG/dx and the diagonal of dG/dq. False (J zero) where dG/dx is singular: the
// determinant relative to the product of its row norms (the volume its rows span against the
// largest they could) is under 1e-12, a forward singularity.
bool implicit_jacobian(const Mat3& dg_dx, const Vec3& dg_dq, int n, Mat3& J) noexcept;

// RT-safe: called every tick. The status of a pose whose x and J (when jacobian_ok) are known:
// kOutsideWorkspace outside the box, then kNearSingularity when J is singular or its inverse
// condition number is under `min_inverse_condition`, else kOk.
Status judge(const Box& box, const Vec3& x, int m, const Mat3& J, bool jacobian_ok,
             double min_inverse_condition) noexcept;

}  // namespace hapticd::kinematics
