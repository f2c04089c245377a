// A three-arm delta with parallelogram shins: the Novint Falcon's geometry as libnifalcon
// describes it (R. E. Stamper's translational 3-DOF manipulator). The numbers are from
// libnifalcon, https://github.com/libnifalcon/libnifalcon, include/falcon/core/FalconGeometry.h
// (a, b, c, d, e, f, r, s, phy[]); the leg equations they enter are those its
// src/kinematic/FalconKinematicStamper.cpp solves. This is our own formulation of them.
//
// Arm i works in its own frame (u, v, w): the world frame (x, y, z) (m) turned by -phi_i about
// z and shifted by (-r, -s, 0), so P = R(-phi_i) x - (r, s, 0) with w = z along the device's
// axis, away from its body. Its motor turns the thigh (length a) in the u-w plane by theta_i
// from the u axis, the joint q_i (rad, libnifalcon's theta1; the driver turns encoder counts
// into it). The shin, a parallelogram of side b, leans out of that plane by a passive angle
// theta3 and carries the effector through the offsets e (knee), d (effector joint), c and f:
//   P_u = a cos theta_i + (d + e + b sin theta3) cos theta2 - c
//   P_v = b cos theta3 - f
//   P_w = a sin theta_i + (d + e + b sin theta3) sin theta2
// so for each arm P_v gives theta3, and the point (P_u + c, P_w) lies at L = d + e +
// b sin theta3 from the knee: G_i(x, q_i) = |(P_u + c, P_w) - a (cos q_i, sin q_i)|^2 - L^2 = 0.
// Of the two knees that solve it, libnifalcon's is the one clockwise of the ray to the point.
#pragma once

#include <numbers>

#include "kinematics/conditioning.h"
#include "kinematics/pose.h"

namespace hapticd::kinematics {

struct DeltaParams {
  // FalconGeometry.h's names in brackets (m, rad).
  double thigh = 0.060;             // [a] motor axis to knee
  double shin = 0.1025;             // [b] the parallelogram's side
  double effector_u = 0.01443;      // [c] shin's effector joint to effector centre, u
  double effector_joint = 0.01125;  // [d] the parallelogram's effector-side offset
  double knee_joint = 0.01125;      // [e] the parallelogram's knee-side offset (= d)
  double effector_v = -0.025;       // [f] shin's effector joint to effector centre, v
  double base_u = 0.0400;           // [r] world origin to the arm's base, u
  double base_v = -0.02309;         // [s] world origin to the arm's base, v
  // [phy] each arm's angle about z: 90, -30 and -150 degrees, each plus the 15 degrees
  // (OFFSET_ANGLE) the device's axes are tilted by.
  double arm_angle[3] = {std::numbers::pi / 2 + std::numbers::pi / 12,
                         -std::numbers::pi / 6 + std::numbers::pi / 12,
                         -5 * std::numbers::pi / 6 + std::numbers::pi / 12};
  // An 8 cm cube about (0, 0, 0.11), where libnifalcon's examples start their guess; every
  // point of it is in reach (every arm's G solvable), the reach ends 5 to 10 mm out.
  Box workspace{Vec3(-0.04, -0.04, 0.07), Vec3(0.04, 0.04, 0.15)};
  Vec3 home = Vec3(0.0, 0.0, 0.11);  // forward kinematics' start when given no guess
  int max_iterations = 8;            // Newton steps of the forward kinematics
  double tolerance = 1e-10;          // rad, largest joint residual accepted
  // kNearSingularity (conditioning.h): sigma_min / sigma_max of J under 0.05 (the box keeps
  // 0.20), or sigma_min under 0.005 m/rad (a twelfth of the thigh: the box keeps 0.017).
  SingularityThresholds near{0.05, 0.005};
};

// RT-safe: called every tick. Closed form; kOutsideWorkspace outside the box or the reach.
JointSolution delta_inverse(const DeltaParams& p, const Vec3& x) noexcept;

// RT-safe: called every tick. Newton's iteration on the three closure constraints G(x, q) = 0
// for the given q, from `guess` (the previous tick's x; p.home when not finite): at most
// p.max_iterations steps, each without inverse trigonometry, kOk only once every joint's
// residual (G_i / dG_i/dq_i, rad to first order) is within p.tolerance and the inverse
// kinematics of the answer gives back q (libnifalcon's knee, not the other, which solves G
// too). Otherwise kNoConvergence, with x the last iterate and J zero. A converged x is then
// judged against the box and the conditioning. J is that of the closure constraints,
// J = -(dG/dx)^-1 dG/dq.
Pose delta_forward(const DeltaParams& p, const Vec3& q, const Vec3& guess) noexcept;

}  // namespace hapticd::kinematics
