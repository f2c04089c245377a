// The vocabulary of the kinematics module: joint positions q (the driver's coordinates, rad or
// m, N <= 3 of them) and a task position x (m, dimension m <= 3), with x = fk(q),
// x' = J(q) q' and tau = J(q)^T F. Vectors and matrices are fixed 3 and 3 x 3 so nothing
// allocates; the actual sizes travel alongside, and what lies outside them is zero (so the
// full 3 x 3 products are the n x m ones).
#pragma once

#include <Eigen/Core>
#include <limits>

#include "base/joints.h"

namespace hapticd::kinematics {

static_assert(base::kMaxJoints == 3, "the kinematics' fixed vectors hold every joint");
using Vec3 = Eigen::Matrix<double, 3, 1>;
using Mat3 = Eigen::Matrix<double, 3, 3>;

enum class Status {
  kOk,
  kOutsideWorkspace,  // outside the configured box, or no assembly / reach for these values
  kNearSingularity,   // J's inverse condition number under the kind's threshold
  kNoConvergence,     // an iterative forward kinematics did not reach its tolerance
};

const char* status_name(Status s) noexcept;

// A forward kinematics answer. x and J are filled for kOk, kOutsideWorkspace (when the
// mechanism assembles) and kNearSingularity (when J is finite); J is zero otherwise, so a force
// mapped through it gives zero torque.
struct Pose {
  Status status = Status::kOk;
  Vec3 x = Vec3::Zero();  // task position, first m entries
  Mat3 J = Mat3::Zero();  // dx/dq, m x n top-left block
  int n = 0;              // joints
  int m = 0;              // task dimension
};

// An inverse kinematics answer: q for x (first n entries), zero when status is not kOk or
// kNearSingularity.
struct JointSolution {
  Status status = Status::kOk;
  Vec3 q = Vec3::Zero();
  int n = 0;
};

// An axis-aligned box on the first `m` coordinates; unbounded by default.
struct Box {
  Vec3 lower = Vec3::Constant(-std::numeric_limits<double>::infinity());
  Vec3 upper = Vec3::Constant(std::numeric_limits<double>::infinity());
};

// RT-safe: called every tick. False for a non-finite coordinate.
bool inside(const Box& box, const Vec3& x, int m) noexcept;

// RT-safe: called every tick. tau = J^T F (first n entries; F's first m).
Vec3 joint_torques(const Pose& pose, const Vec3& force) noexcept;

// RT-safe: called every tick. x' = J q' (first m entries).
Vec3 task_velocity(const Pose& pose, const Vec3& joint_velocity) noexcept;

}  // namespace hapticd::kinematics
