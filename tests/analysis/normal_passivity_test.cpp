// The device's damping along a wall's normal and the corner condition (normal_passivity.h):
// closed forms for independent joints and a gantry, the least-dissipation claim checked by
// brute force on random devices, and the corner that needs more than each of its walls.
#include "analysis/normal_passivity.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <array>
#include <cmath>
#include <limits>
#include <random>

namespace hapticd::analysis {
namespace {

DeviceDamping joints(int n, Vec3 b) {
  DeviceDamping d;
  d.m = d.n = n;
  d.jacobian = Mat3::Identity();
  d.joint_damping = b;
  return d;
}

TEST(NormalPassivity, OneAxisIsTheDevicesOwnDampingEitherWay) {
  const DeviceDamping d = joints(1, Vec3(0.7, 0, 0));
  EXPECT_DOUBLE_EQ(normal_damping(d, Vec3(1, 0, 0)), 0.7);
  EXPECT_DOUBLE_EQ(normal_damping(d, Vec3(-1, 0, 0)), 0.7);
  const std::array<NormalDemand, 1> wall{{{Vec3(1, 0, 0), 0.5}}};
  EXPECT_NEAR(contact_margin(d, wall), 0.2, 1e-15);
}

TEST(NormalPassivity, TwoJointsAlongADiagonalAddTheirMobilities) {
  const DeviceDamping d = joints(2, Vec3(1.0, 4.0, 0));
  for (double a : {0.0, 0.3, 0.7854, 1.2, 1.5708}) {
    const Vec3 n(std::cos(a), std::sin(a), 0);
    const double expected = 1.0 / (std::pow(std::cos(a), 2) / 1.0 + std::pow(std::sin(a), 2) / 4.0);
    EXPECT_NEAR(normal_damping(d, n), expected, 1e-12) << a;
    EXPECT_NEAR(normal_damping(d, 3.0 * n), expected, 1e-12) << "a normal's length is not b's";
  }
}

TEST(NormalPassivity, AGantryScrewDividesItsDampingByTheSquareOfItsLead) {
  // A joint of 0.002 N m s/rad driving 0.01 m/rad: 0.002 / 0.01^2 = 20 N s/m along its axis.
  DeviceDamping d = joints(2, Vec3(0.002, 0.002, 0));
  d.jacobian.diagonal() << 0.01, -0.01, 1;
  EXPECT_NEAR(normal_damping(d, Vec3(1, 0, 0)), 20.0, 1e-9);
  EXPECT_NEAR(normal_damping(d, Vec3(0, 1, 0)), 20.0, 1e-9) << "a sign does not damp less";
}

// Of every joint velocity with n^T J q' = 1, none dissipates less than b_n, and one does.
TEST(NormalPassivity, NoJointMotionAlongTheNormalDissipatesLessThanBn) {
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.1, 2.0);
  for (int trial = 0; trial < 50; ++trial) {
    DeviceDamping d;
    d.m = d.n = 3;
    for (int i = 0; i < 9; ++i) d.jacobian(i / 3, i % 3) = u(rng);
    d.joint_damping = Vec3(pos(rng), pos(rng), pos(rng));
    const Vec3 n = Vec3(u(rng), u(rng), u(rng)).normalized();
    const double bn = normal_damping(d, n);
    const Mat3 B = d.joint_damping.asDiagonal();
    const Vec3 g = d.jacobian.transpose() * n;  // n^T J q' = g^T q'
    const Vec3 best = B.inverse() * g / g.dot(B.inverse() * g);
    EXPECT_NEAR(best.dot(B * best), bn, 1e-9 * bn) << "the least-dissipating motion";
    for (int k = 0; k < 200; ++k) {
      Vec3 q = best + Vec3(u(rng), u(rng), u(rng));
      q -= (g.dot(q) - 1.0) / g.squaredNorm() * g;  // back onto n^T J q' = 1
      EXPECT_GE(q.dot(B * q), bn * (1 - 1e-12));
    }
    // One wall: the corner condition is b_req <= b_n, nothing more.
    const std::array<NormalDemand, 1> at{{{n, 0.999 * bn}}}, over{{{n, 1.001 * bn}}};
    EXPECT_GE(contact_margin(d, at), 0.0);
    EXPECT_LT(contact_margin(d, over), 0.0);
  }
}

// Two walls meeting at 45 degrees on a device damped b in every direction: each alone needs
// only b >= b_req, together b >= (1 + 1/sqrt 2) b_req (the eigenvalues of b I - b_req (e1 e1^T +
// n n^T) are b - b_req (1 +- 1/sqrt 2)).
TEST(NormalPassivity, ACornerNeedsMoreThanEachOfItsWalls) {
  const double b = 1.0, req = 0.6;
  const DeviceDamping d = joints(2, Vec3(b, b, 0));
  const Vec3 diagonal = Vec3(1, 1, 0) / std::sqrt(2.0);
  const std::array<NormalDemand, 1> one{{{Vec3(1, 0, 0), req}}}, other{{{diagonal, req}}};
  const std::array<NormalDemand, 2> both{{{Vec3(1, 0, 0), req}, {diagonal, req}}};
  EXPECT_NEAR(contact_margin(d, one), b - req, 1e-12);
  EXPECT_NEAR(contact_margin(d, other), b - req, 1e-12);
  EXPECT_NEAR(contact_margin(d, both), b - req * (1 + 1 / std::sqrt(2.0)), 1e-12);
  EXPECT_LT(contact_margin(d, both), 0.0) << "0.6 passes alone, not in the corner";
  // Opposite faces of a box (a slot) cannot both be pressed into: still summed, conservative.
  const std::array<NormalDemand, 2> slot{{{Vec3(1, 0, 0), req}, {Vec3(-1, 0, 0), req}}};
  EXPECT_NEAR(contact_margin(d, slot), b - 2 * req, 1e-12);
}

TEST(NormalPassivity, ASingularOrUndampedDeviceIsNeverCovered) {
  DeviceDamping d = joints(2, Vec3(1, 1, 0));
  d.jacobian.col(1) = d.jacobian.col(0);  // both joints move along x: no y motion at all
  Mat3 b_c;
  EXPECT_FALSE(task_damping(d, b_c));
  const std::array<NormalDemand, 1> wall{{{Vec3(1, 0, 0), 0.1}}};
  EXPECT_EQ(contact_margin(d, wall), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(normal_damping(d, Vec3(0, 1, 0)), std::numeric_limits<double>::infinity())
      << "no motion along y: the wall there does no work";
  EXPECT_NEAR(normal_damping(d, Vec3(1, 0, 0)), 0.5, 1e-12) << "two joints of 1 share x";
  const DeviceDamping free = joints(2, Vec3(1, 0, 0));
  EXPECT_EQ(normal_damping(free, Vec3(0, 1, 0)), 0.0);
  EXPECT_FALSE(task_damping(free, b_c));
}

TEST(NormalPassivity, NonFiniteInputIsNeverANumberThatPasses) {
  DeviceDamping d = joints(2, Vec3(1, 1, 0));
  EXPECT_TRUE(std::isnan(normal_damping(d, Vec3(std::nan(""), 0, 0))));
  d.jacobian(0, 1) = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(std::isnan(normal_damping(d, Vec3(1, 0, 0))));
  const std::array<NormalDemand, 1> wall{{{Vec3(1, 0, 0), 0.1}}};
  EXPECT_EQ(contact_margin(d, wall), -std::numeric_limits<double>::infinity());
  const DeviceDamping ok = joints(2, Vec3(1, 1, 0));
  const std::array<NormalDemand, 1> nan_req{{{Vec3(1, 0, 0), std::nan("")}}};
  EXPECT_EQ(contact_margin(ok, nan_req), -std::numeric_limits<double>::infinity());
}

// A planar device (m = 2) under a wall tilted out of its plane, and one axis driven by two
// joints (n > m): b_n and the one-wall margin agree, counting the normal's whole length.
TEST(NormalPassivity, ATiltedNormalAndARedundantDeviceAgreeWithTheMargin) {
  DeviceDamping planar = joints(2, Vec3(1.0, 1.0, 0));
  const Vec3 tilted = Vec3(1, 0, 1) / std::sqrt(2.0);  // half of it along z, where nothing moves
  EXPECT_NEAR(normal_damping(planar, tilted), 2.0, 1e-12) << "1 / (n^T J B^-1 J^T n) = 1 / 0.5";
  const std::array<NormalDemand, 1> under{{{tilted, 1.9}}}, over{{{tilted, 2.1}}};
  EXPECT_GE(contact_margin(planar, under), 0.0);
  EXPECT_LT(contact_margin(planar, over), 0.0);
  // Two joints of damping 1 and 3 both moving x (m = 1, n = 2): B_c = 1 / (1/1 + 1/3).
  DeviceDamping redundant;
  redundant.m = 1;
  redundant.n = 2;
  redundant.jacobian.setZero();
  redundant.jacobian(0, 0) = redundant.jacobian(0, 1) = 1.0;
  redundant.joint_damping = Vec3(1.0, 3.0, 0);
  EXPECT_NEAR(normal_damping(redundant, Vec3(1, 0, 0)), 0.75, 1e-12);
  const std::array<NormalDemand, 1> at{{{Vec3(1, 0, 0), 0.74}}}, past{{{Vec3(1, 0, 0), 0.76}}};
  EXPECT_GE(contact_margin(redundant, at), 0.0);
  EXPECT_LT(contact_margin(redundant, past), 0.0);
}

TEST(NormalPassivity, AWallWithoutANormalIsNoWallThatPasses) {
  const DeviceDamping d = joints(2, Vec3(1, 1, 0));
  EXPECT_TRUE(std::isnan(normal_damping(d, Vec3::Zero())));
  const std::array<NormalDemand, 1> none{{{Vec3::Zero(), 0.1}}};
  EXPECT_EQ(contact_margin(d, none), -std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace hapticd::analysis
