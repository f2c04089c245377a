// The two kinds without geometry: N independent joints (today's one-axis device) and a gantry.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "check.h"
#include "kinematics/conditioning.h"
#include "kinematics/kinematics.h"

namespace hapticd::kinematics {
namespace {

TEST(Joints, OneAxisIsTheIdentity) {
  Kinematics k;  // joints, n = 1: today's device
  const Pose pose = forward(k, Vec3(0.0125, 7.0, 7.0), Vec3::Zero());
  EXPECT_EQ(pose.status, Status::kOk);
  EXPECT_EQ(pose.n, 1);
  EXPECT_EQ(pose.m, 1);
  EXPECT_EQ(pose.x, Vec3(0.0125, 0.0, 0.0)) << "entries past n are not the device's";
  EXPECT_EQ(pose.J, Mat3(Vec3(1, 0, 0).asDiagonal()));
  // The force on the one axis is its joint's force; a force on an axis it lacks is none.
  EXPECT_EQ(joint_torques(pose, Vec3(-2.5, 9.0, 9.0)), Vec3(-2.5, 0.0, 0.0));
  const JointSolution back = inverse(k, pose.x);
  EXPECT_EQ(back.status, Status::kOk);
  EXPECT_DOUBLE_EQ(back.q[0], 0.0125);
}

TEST(Joints, RangesAreTheWorkspace) {
  Kinematics k;
  k.joints.n = 2;
  k.joints.workspace = Box{Vec3(-1.0, -0.5, 0.0), Vec3(1.0, 0.5, 0.0)};
  EXPECT_EQ(forward(k, Vec3(0.9, 0.4, 0.0), Vec3::Zero()).status, Status::kOk);
  EXPECT_EQ(forward(k, Vec3(0.9, 0.6, 0.0), Vec3::Zero()).status, Status::kOutsideWorkspace);
  EXPECT_EQ(forward(k, Vec3(std::nan(""), 0.0, 0.0), Vec3::Zero()).status,
            Status::kOutsideWorkspace)
      << "a non-finite joint is never inside";
  EXPECT_EQ(inverse(k, Vec3(-1.5, 0.0, 0.0)).status, Status::kOutsideWorkspace);
}

// The default box is unbounded: an infinite joint (an overflowed count) is still no position.
TEST(Joints, AnInfiniteJointIsOutsideEvenAnUnboundedBox) {
  Kinematics k;
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(forward(k, Vec3(inf, 0.0, 0.0), Vec3::Zero()).status, Status::kOutsideWorkspace);
  EXPECT_EQ(forward(k, Vec3(-inf, 0.0, 0.0), Vec3::Zero()).status, Status::kOutsideWorkspace);
  EXPECT_EQ(inverse(k, Vec3(inf, 0.0, 0.0)).status, Status::kOutsideWorkspace);
}

// A J that moves nothing is singular whatever the thresholds, zero ones included.
TEST(Joints, AZeroJacobianIsNearASingularityEvenWithZeroThresholds) {
  EXPECT_EQ(judge(Box{}, Vec3::Zero(), 2, Mat3::Zero(), true, SingularityThresholds{}),
            Status::kNearSingularity);
  EXPECT_EQ(judge(Box{}, Vec3::Zero(), 2, Mat3::Identity(), true, SingularityThresholds{}),
            Status::kOk);
}

Kinematics gantry() {
  Kinematics k;
  k.kind = Kind::kCartesian;
  k.cartesian.n = 3;
  k.cartesian.scale = Vec3(0.01, 0.02, 0.005);  // m per rad: belts and a screw
  k.cartesian.sign = Vec3(1.0, -1.0, 1.0);
  k.cartesian.workspace = Box{Vec3(-0.2, -0.2, 0.0), Vec3(0.2, 0.2, 0.1)};
  return k;
}

TEST(Cartesian, ANegativeSignMovesTheAxisNegative) {
  const Kinematics k = gantry();
  const Pose at = forward(k, Vec3(1.0, 1.0, 1.0), Vec3::Zero());
  const Pose moved = forward(k, Vec3(1.0, 1.5, 1.0), Vec3::Zero());  // +0.5 rad on joint 1
  ASSERT_EQ(moved.status, Status::kOk);
  EXPECT_NEAR(moved.x[1] - at.x[1], -0.01, 1e-15)
      << "sign -1: a positive joint motion moves y down";
  EXPECT_DOUBLE_EQ(moved.x[0], at.x[0]);
  EXPECT_NEAR(moved.x[0], 0.01, 1e-15);
  EXPECT_NEAR(task_velocity(at, Vec3(0.0, 2.0, 0.0))[1], -0.04, 1e-15);
  // Pushing +y takes a negative torque on that joint (the joint must turn negative).
  EXPECT_NEAR(joint_torques(at, Vec3(0.0, 10.0, 0.0))[1], -0.2, 1e-15);
}

TEST(Cartesian, InverseUndoesForwardAndTheBoxIsKept) {
  const Kinematics k = gantry();
  const Vec3 x(0.05, -0.12, 0.03);
  const JointSolution s = inverse(k, x);
  ASSERT_EQ(s.status, Status::kOk);
  EXPECT_TRUE(forward(k, s.q, Vec3::Zero()).x.isApprox(x, 1e-15));
  EXPECT_EQ(inverse(k, Vec3(0.05, -0.12, 0.11)).status, Status::kOutsideWorkspace);
  EXPECT_EQ(forward(k, Vec3(0.0, 0.0, 25.0), Vec3::Zero()).status, Status::kOutsideWorkspace)
      << "25 rad of the screw is 12.5 cm, past the 10 cm of z";
}

TEST(Kinematics, InvalidParametersAreNamed) {
  Kinematics k = gantry();
  EXPECT_EQ(invalid_reason(k), nullptr);
  k.cartesian.sign[2] = 0.5;
  EXPECT_STREQ(invalid_reason(k), "cartesian: every sign must be +1 or -1");
  k = Kinematics{};
  k.joints.n = 4;
  EXPECT_NE(invalid_reason(k), nullptr);
  k = Kinematics{};
  k.kind = Kind::kPantograph;
  EXPECT_EQ(invalid_reason(k), nullptr);
  k.pantograph.distal[1] = -0.1;
  EXPECT_NE(invalid_reason(k), nullptr);
  k = Kinematics{};
  k.kind = Kind::kDelta;
  EXPECT_EQ(invalid_reason(k), nullptr);
  EXPECT_EQ(joint_count(k), 3);
  k.delta.max_iterations = 0;
  EXPECT_NE(invalid_reason(k), nullptr);
}

}  // namespace
}  // namespace hapticd::kinematics
