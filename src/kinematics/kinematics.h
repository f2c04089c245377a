// The kinematics of a device: which kind it is and that kind's parameters, and the two
// directions every kind answers, dispatched on the kind. Free functions over value types:
// no I/O, no allocation, no exception.
#pragma once

#include "kinematics/cartesian.h"
#include "kinematics/delta.h"
#include "kinematics/joints.h"
#include "kinematics/pantograph.h"
#include "kinematics/pose.h"

namespace hapticd::kinematics {

enum class Kind { kJoints, kCartesian, kPantograph, kDelta };

const char* kind_name(Kind k) noexcept;

// Only the parameters of `kind` are read.
struct Kinematics {
  Kind kind = Kind::kJoints;
  JointsParams joints;
  CartesianParams cartesian;
  PantographParams pantograph;
  DeltaParams delta;
};

// Joints n and task dimension m of the kind (equal for every kind here).
int joint_count(const Kinematics& k) noexcept;

// The kind's workspace box (on the joints' own coordinates for `joints`).
const Box& workspace(const Kinematics& k) noexcept;
Box& workspace(Kinematics& k) noexcept;
// Its centre on each coordinate the box bounds on both sides, 0 on the others.
Vec3 workspace_centre(const Kinematics& k) noexcept;

// Why these parameters describe no mechanism (a size out of 1..3, a length, scale or limit
// that is not positive and finite, a sign not +-1, an empty box), or nullptr when they do.
const char* invalid_reason(const Kinematics& k) noexcept;

// RT-safe: called every tick. x and J at q; `guess` is the previous tick's x (used by the
// delta's iteration only; a non-finite guess starts it from its home).
Pose forward(const Kinematics& k, const Vec3& q, const Vec3& guess) noexcept;

// RT-safe: called every tick.
JointSolution inverse(const Kinematics& k, const Vec3& x) noexcept;

}  // namespace hapticd::kinematics
