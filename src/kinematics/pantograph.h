// A planar five-bar pantograph. Two motors sit on the x axis at (-d/2, 0) (joint 0, the left)
// and (+d/2, 0) (joint 1, the right), d the base separation. Each turns a proximal link of
// length a_i; q_i is that link's angle from the +x axis, counter-clockwise (rad). Two distal
// links of length b_i run from the elbows E_i = B_i + a_i (cos q_i, sin q_i) and meet at the
// end effector x = (x, y) (m), m = 2.
//
// Working mode, chosen here once for both directions: the end effector is on the far side of
// the elbows from the base (on the left of the ray E_0 -> E_1, so y > 0 for a device held
// upright), and the elbows point out (the left elbow counter-clockwise of the ray B_0 -> x, the
// right one clockwise of B_1 -> x). Forward kinematics takes that intersection of the two
// distal circles; inverse kinematics gives those elbows. Within the mode the singularities are
// where a proximal and its distal link fold onto or stretch along each other (J loses rank)
// and where the two distal links line up (J grows without bound).
#pragma once

#include "kinematics/conditioning.h"
#include "kinematics/pose.h"

namespace hapticd::kinematics {

struct PantographParams {
  // An example geometry (of no particular device): 10 cm proximal, 13 cm distal links, motors
  // 5 cm apart; its box is well inside the reach of this geometry and away from its
  // singularities.
  double proximal[2] = {0.10, 0.10};                             // a_0, a_1 (m)
  double distal[2] = {0.13, 0.13};                               // b_0, b_1 (m)
  double base_separation = 0.05;                                 // d (m)
  Box workspace{Vec3(-0.08, 0.08, 0.0), Vec3(0.08, 0.19, 0.0)};  // on (x, y) (m)
  // kNearSingularity (conditioning.h): sigma_min / sigma_max of J under 0.05 (the box keeps
  // 0.41), or sigma_min under 0.01 m/rad (10 % of the proximal links: the box keeps 0.049).
  SingularityThresholds near{0.05, 0.01};
};

// RT-safe: called every tick. Circle intersection, closed form; kOutsideWorkspace with J zero
// when the distal links cannot meet (q not of this mechanism).
Pose pantograph_forward(const PantographParams& p, const Vec3& q) noexcept;

// RT-safe: called every tick. Closed form; kOutsideWorkspace when x is outside the box or
// beyond a leg's reach.
JointSolution pantograph_inverse(const PantographParams& p, const Vec3& x) noexcept;

}  // namespace hapticd::kinematics
