// The five-bar pantograph against what a user of it sees: inverse then forward returns the
// point, J is the derivative of the forward kinematics, J^T does the same virtual work, and a
// leg stretched straight or folded is reported as near a singularity.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "check.h"
#include "kinematics/pantograph.h"

namespace hapticd::kinematics {
namespace {

using testing::numeric_jacobian;
using testing::relative_error;

const PantographParams kParams;  // the example geometry and its box

Vec3 fk(const PantographParams& p, const Vec3& q) { return pantograph_forward(p, q).x; }

// A 9 x 9 grid over the example's box.
template <typename F>
void over_the_box(F f) {
  testing::over_box(kParams.workspace, 2, 9, f);
}

TEST(Pantograph, ForwardOfInverseIsThePointOverTheBox) {
  over_the_box([](const Vec3& x) {
    const JointSolution s = pantograph_inverse(kParams, x);
    ASSERT_EQ(s.status, Status::kOk) << x.transpose();
    const Pose pose = pantograph_forward(kParams, s.q);
    EXPECT_EQ(pose.status, Status::kOk)
        << "the example box is clear of singularities at " << x.transpose();
    EXPECT_LT((pose.x - x).norm(), 1e-12) << x.transpose();
  });
}

TEST(Pantograph, ElbowsPointOutAndTheEffectorIsAboveThem) {
  const JointSolution s = pantograph_inverse(kParams, Vec3(0.0, 0.15, 0.0));
  ASSERT_EQ(s.status, Status::kOk);
  // Symmetric about the y axis: the left elbow left of its base, the right one right of its.
  EXPECT_GT(s.q[0], std::numbers::pi / 2);
  EXPECT_LT(s.q[1], std::numbers::pi / 2);
  EXPECT_NEAR(s.q[0] + s.q[1], std::numbers::pi, 1e-12);
}

TEST(Pantograph, JacobianIsTheDerivativeOfForwardKinematics) {
  over_the_box([](const Vec3& x) {
    const Vec3 q = pantograph_inverse(kParams, x).q;
    const Mat3 numeric = numeric_jacobian([](const Vec3& v) { return fk(kParams, v); }, q, 2, 1e-6);
    EXPECT_LT(relative_error(pantograph_forward(kParams, q).J, numeric), 1e-6) << x.transpose();
  });
}

TEST(Pantograph, TransposeDoesTheSameVirtualWork) {
  const Vec3 q = pantograph_inverse(kParams, Vec3(0.03, 0.12, 0.0)).q;
  const Pose pose = pantograph_forward(kParams, q);
  const Vec3 force(1.5, -4.0, 0.0);  // N
  const Vec3 tau = joint_torques(pose, force);
  const Vec3 dq(1e-5, -2e-5, 0.0);
  const Vec3 dx = fk(kParams, q + dq) - fk(kParams, q - dq);  // the motion itself, not J dq
  const double work = force.dot(dx);
  EXPECT_NEAR(tau.dot(2 * dq), work, 1e-9 * std::abs(work));
  EXPECT_EQ(tau[2], 0.0);
}

// A pantograph whose box is the whole plane, to reach its singular poses.
PantographParams unbounded() {
  PantographParams p;
  p.workspace = Box{};
  return p;
}

TEST(Pantograph, ALegStretchedStraightIsNearASingularity) {
  const PantographParams p = unbounded();
  // The left leg stretched to within 1 um of its full reach, straight up and to the right.
  const double reach = p.proximal[0] + p.distal[0] - 1e-6;
  const Vec3 x =
      Vec3(-p.base_separation / 2, 0.0, 0.0) + reach * Vec3(0.3, 0.954, 0.0).normalized();
  const JointSolution s = pantograph_inverse(p, x);
  ASSERT_EQ(s.status, Status::kOk);
  const Pose pose = pantograph_forward(p, s.q);
  EXPECT_LT((pose.x - x).norm(), 1e-9);
  EXPECT_EQ(pose.status, Status::kNearSingularity);
}

TEST(Pantograph, ALegFoldedIsNearASingularity) {
  const PantographParams p = unbounded();
  // The right leg folded: its distal link back along its proximal one, the effector 1 um
  // beyond the shortest reach b - a, above the right motor.
  const double reach = p.distal[1] - p.proximal[1] + 1e-6;
  const Vec3 x(p.base_separation / 2, reach, 0.0);
  const JointSolution s = pantograph_inverse(p, x);
  ASSERT_EQ(s.status, Status::kOk);
  const Pose pose = pantograph_forward(p, s.q);
  ASSERT_LT((pose.x - x).norm(), 1e-9) << "the same assembly";
  EXPECT_EQ(pose.status, Status::kNearSingularity);
}

TEST(Pantograph, OutsideTheBoxOrTheReach) {
  EXPECT_EQ(pantograph_inverse(kParams, Vec3(0.0, 0.2, 0.0)).status, Status::kOutsideWorkspace);
  EXPECT_EQ(pantograph_inverse(unbounded(), Vec3(0.0, 0.3, 0.0)).status, Status::kOutsideWorkspace)
      << "beyond both legs' reach";
  // Inside the reach but above the box: forward still gives the point, flagged.
  const Vec3 above(0.0, 0.2, 0.0);
  const Pose pose = pantograph_forward(kParams, pantograph_inverse(unbounded(), above).q);
  EXPECT_EQ(pose.status, Status::kOutsideWorkspace);
  EXPECT_LT((pose.x - above).norm(), 1e-12);
  // Elbows pointing away from each other, further apart than two short distal links reach:
  // the links cannot meet, and no force goes through.
  PantographParams short_distal = kParams;
  short_distal.distal[0] = short_distal.distal[1] = 0.05;
  const Pose apart = pantograph_forward(short_distal, Vec3(std::numbers::pi, 0.0, 0.0));
  EXPECT_EQ(apart.status, Status::kOutsideWorkspace);
  EXPECT_EQ(joint_torques(apart, Vec3(1.0, 1.0, 0.0)), Vec3::Zero());
}

}  // namespace
}  // namespace hapticd::kinematics
