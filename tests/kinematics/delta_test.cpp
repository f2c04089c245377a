// The Falcon-geometry delta against what a user of it sees: the joint angles libnifalcon's
// equations give, forward of inverse over the workspace, J as the derivative of the forward
// kinematics, J^T doing the same virtual work, and an iteration that says when it failed.
#include <gtest/gtest.h>

#include <cmath>

#include "check.h"
#include "kinematics/delta.h"

namespace hapticd::kinematics {
namespace {

using testing::numeric_jacobian;
using testing::relative_error;

const DeltaParams kFalcon;

// An n^3 grid over the Falcon's default box.
template <typename F>
void over_the_box(int n, F f) {
  testing::over_box(kFalcon.workspace, 3, n, f);
}

// The joint angles of libnifalcon's FalconKinematicStamper::IK (its tan-half-angle quadratic,
// evaluated separately in double precision for the same geometry): the same knee, frame and
// zero of theta1 as ours.
TEST(Delta, InverseKinematicsAgreesWithLibnifalcon) {
  struct Case {
    Vec3 x, q;
  };
  const Case cases[] = {
      {Vec3(0.0, 0.0, 0.11), Vec3(0.282533201, 0.282533201, 0.282533201)},
      {Vec3(0.03, -0.02, 0.09), Vec3(0.501838200, -0.436271458, 0.217992034)},
      {Vec3(-0.035, 0.025, 0.14), Vec3(0.469896001, 1.151155778, 0.787410620)},
  };
  for (const Case& c : cases) {
    const JointSolution s = delta_inverse(kFalcon, c.x);
    ASSERT_EQ(s.status, Status::kOk) << c.x.transpose();
    EXPECT_LT((s.q - c.q).cwiseAbs().maxCoeff(), 1e-6) << c.x.transpose();
  }
}

TEST(Delta, ForwardOfInverseIsThePointOverTheBox) {
  over_the_box(9, [](const Vec3& x) {
    const JointSolution s = delta_inverse(kFalcon, x);
    ASSERT_EQ(s.status, Status::kOk) << x.transpose();
    // From the home position, as at the first tick: the whole box within 8 iterations.
    const Pose pose = delta_forward(kFalcon, s.q, kFalcon.home);
    EXPECT_EQ(pose.status, Status::kOk) << x.transpose();
    EXPECT_LT((pose.x - x).norm(), 1e-9) << x.transpose();
  });
}

TEST(Delta, FromThePreviousTickThreeIterationsSuffice) {
  DeltaParams p = kFalcon;
  p.max_iterations = 3;
  over_the_box(5, [&p](const Vec3& x) {
    // 1 mm away: a 1 m/s motion at 1 kHz.
    const Vec3 previous = x + Vec3(0.0006, -0.0006, 0.0006);
    const Pose pose = delta_forward(p, delta_inverse(p, x).q, previous);
    EXPECT_EQ(pose.status, Status::kOk) << x.transpose();
    EXPECT_LT((pose.x - x).norm(), 1e-9) << x.transpose();
  });
}

// The forward kinematics solved tightly, for differences.
Vec3 fk_tight(const Vec3& q) {
  DeltaParams p = kFalcon;
  p.tolerance = 1e-14;
  p.max_iterations = 20;
  p.workspace = Box{};
  return delta_forward(p, q, p.home).x;
}

TEST(Delta, JacobianIsTheDerivativeOfForwardKinematics) {
  over_the_box(5, [](const Vec3& x) {
    const Vec3 q = delta_inverse(kFalcon, x).q;
    const Mat3 numeric = numeric_jacobian(fk_tight, q, 3, 1e-6);
    const Pose pose = delta_forward(kFalcon, q, kFalcon.home);
    EXPECT_LT(relative_error(pose.J, numeric), 1e-6) << x.transpose();
  });
}

TEST(Delta, TransposeDoesTheSameVirtualWork) {
  const Vec3 q = delta_inverse(kFalcon, Vec3(0.01, 0.02, 0.12)).q;
  const Pose pose = delta_forward(kFalcon, q, kFalcon.home);
  ASSERT_EQ(pose.status, Status::kOk);
  const Vec3 force(2.0, -1.0, 3.0);  // N
  const Vec3 tau = joint_torques(pose, force);
  const Vec3 dq(1e-5, -2e-5, 1.5e-5);
  const double work = force.dot(fk_tight(q + dq) - fk_tight(q - dq));
  EXPECT_NEAR(tau.dot(2 * dq), work, 1e-8 * std::abs(work));
}

TEST(Delta, OneIterationFromFarIsNoConvergenceNeverAWrongAnswer) {
  DeltaParams p = kFalcon;
  p.max_iterations = 1;
  const Vec3 q = delta_inverse(p, Vec3(0.035, 0.035, 0.08)).q;
  const Pose pose = delta_forward(p, q, Vec3(-0.035, -0.035, 0.14));
  EXPECT_EQ(pose.status, Status::kNoConvergence);
  EXPECT_EQ(joint_torques(pose, Vec3(1.0, 1.0, 1.0)), Vec3::Zero()) << "no force through it";
  // Given its 8 iterations, the same start converges.
  EXPECT_EQ(delta_forward(kFalcon, q, Vec3(-0.035, -0.035, 0.14)).status, Status::kOk);
}

TEST(Delta, AStartFarOutOfTheBoxStillFindsThePointANonFiniteJointNever) {
  const Vec3 x(0.0, 0.0, 0.11);
  const Vec3 q = delta_inverse(kFalcon, x).q;
  // The closure constraints are defined wherever each shin reaches its v: from 39 cm beyond
  // the box the iteration still lands on the point, and on the right knee.
  const Pose far = delta_forward(kFalcon, q, Vec3(0.0, 0.0, 0.5));
  EXPECT_EQ(far.status, Status::kOk);
  EXPECT_LT((far.x - x).norm(), 1e-9);
  // Where a shin cannot reach, there is nothing to iterate on.
  EXPECT_EQ(delta_forward(kFalcon, q, Vec3(0.0, 0.5, 0.11)).status, Status::kNoConvergence);
  EXPECT_EQ(delta_forward(kFalcon, Vec3(q[0], std::nan(""), q[2]), kFalcon.home).status,
            Status::kNoConvergence);
  // A non-finite guess starts from home instead.
  EXPECT_EQ(delta_forward(kFalcon, q, Vec3::Constant(std::nan(""))).status, Status::kOk);
}

TEST(Delta, OutsideTheBoxIsReportedWithThePoint) {
  EXPECT_EQ(delta_inverse(kFalcon, Vec3(0.0, 0.0, 0.2)).status, Status::kOutsideWorkspace);
  DeltaParams unbounded = kFalcon;
  unbounded.workspace = Box{};
  EXPECT_EQ(delta_inverse(unbounded, Vec3(0.0, 0.0, 0.3)).status, Status::kOutsideWorkspace)
      << "beyond the arms' reach";
  const Vec3 beside(0.044, 0.0, 0.11);  // in reach, 4 mm past the box
  const JointSolution s = delta_inverse(unbounded, beside);
  ASSERT_EQ(s.status, Status::kOk);
  const Pose pose = delta_forward(kFalcon, s.q, kFalcon.home);
  EXPECT_EQ(pose.status, Status::kOutsideWorkspace);
  EXPECT_LT((pose.x - beside).norm(), 1e-9);
}

TEST(Delta, TheEdgeOfTheReachIsNearASingularity) {
  DeltaParams p = kFalcon;
  p.workspace = Box{};
  // Up the z axis to where the arms stretch straight (bisected), then 1 nm back inside.
  double in = 0.15, out = 0.25;
  for (int i = 0; i < 60; ++i) {
    const double mid = (in + out) / 2;
    (delta_inverse(p, Vec3(0.0, 0.0, mid)).status == Status::kOk ? in : out) = mid;
  }
  const Vec3 edge(0.0, 0.0, in - 1e-9);
  const Pose pose = delta_forward(p, delta_inverse(p, edge).q, edge);
  EXPECT_EQ(pose.status, Status::kNearSingularity) << "z " << edge.z();
  // The Falcon's own box stays clear of it.
  EXPECT_EQ(delta_forward(kFalcon, delta_inverse(kFalcon, Vec3(0.0, 0.0, 0.149)).q, edge).status,
            Status::kOk);
}

// The joint angles of x on the other knee of each arm (the second root of the thigh-shin
// closure, counter-clockwise of the ray to the point): G(x, q) = 0 there as well.
Vec3 other_knee(const DeltaParams& p, const Vec3& x) {
  Vec3 q;
  for (int i = 0; i < 3; ++i) {
    const double cp = std::cos(p.arm_angle[i]), sp = std::sin(p.arm_angle[i]);
    const double pu = cp * x.x() + sp * x.y() - p.base_u + p.effector_u;
    const double pv = -sp * x.x() + cp * x.y() - p.base_v + p.effector_v;
    const double reach = p.knee_joint + p.effector_joint + std::sqrt(p.shin * p.shin - pv * pv);
    const double rho = std::hypot(pu, x.z());
    const double c = (rho * rho + p.thigh * p.thigh - reach * reach) / (2 * p.thigh * rho);
    q[i] = std::atan2(x.z(), pu) + std::acos(c);
  }
  return q;
}

// Started on the point of q's other knee, the iteration is already converged there: that is
// never kOk, and the next tick does not start from it again (it would be stuck for good).
TEST(Delta, ThePointOfTheOtherKneeIsNeverTheAnswerNorTheNextStart) {
  over_the_box(3, [](const Vec3& x) {
    const Vec3 q = other_knee(kFalcon, x);
    const Pose pose = delta_forward(kFalcon, q, x);
    // The next start is home (which at home itself is the point again: a measure-zero q).
    if ((x - kFalcon.home).norm() > 1e-9) {
      EXPECT_GT((pose.x - x).norm(), 1e-6) << x.transpose();
    }
    if (pose.status == Status::kOk) {
      EXPECT_LT((delta_inverse(kFalcon, pose.x).q - q).cwiseAbs().maxCoeff(), 1e-6)
          << "an answer is a point of q on libnifalcon's knee";
    }
  });
}

}  // namespace
}  // namespace hapticd::kinematics
