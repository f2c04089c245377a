// Saturation keeps the force's direction and every joint within its limit.
#include "kinematics/saturation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace hapticd::kinematics {
namespace {

TEST(Saturation, WithinTheLimitsNothingChanges) {
  const Saturated s = saturate(Vec3(0.5, -1.0, 0.2), Vec3(1.0, 1.0, 1.0), 3);
  EXPECT_EQ(s.status, SaturationStatus::kWithin);
  EXPECT_EQ(s.tau, Vec3(0.5, -1.0, 0.2));
  EXPECT_EQ(s.scale, 1.0);
}

TEST(Saturation, OverALimitTheWholeVectorScalesKeepingItsDirection) {
  const Vec3 tau(3.0, -0.9, 1.6);
  const Vec3 limit(2.0, 0.5, 1.0);  // joint 1 is 1.8 times over, joint 2 1.6, joint 0 1.5
  const Saturated s = saturate(tau, limit, 3);
  EXPECT_EQ(s.status, SaturationStatus::kSaturated);
  for (int i = 0; i < 3; ++i) EXPECT_LE(std::abs(s.tau[i]), limit[i]) << i;
  EXPECT_DOUBLE_EQ(std::abs(s.tau[1]), 0.5) << "the worst joint lands on its limit";
  EXPECT_NEAR(s.tau.normalized().dot(tau.normalized()), 1.0, 1e-15) << "same direction";
  EXPECT_NEAR(s.scale, 0.5 / 0.9, 1e-15);
}

TEST(Saturation, BoundsEveryJointOverManyVectors) {
  const Vec3 limit(0.3, 0.7, 0.05);
  for (int k = 0; k < 1000; ++k) {
    const Vec3 tau(std::sin(k * 1.3) * 2, std::cos(k * 0.7) * 3, std::sin(k * 0.11) * 0.2);
    const Saturated s = saturate(tau, limit, 3);
    for (int i = 0; i < 3; ++i) ASSERT_LE(std::abs(s.tau[i]), limit[i]) << k;
    ASSERT_NEAR(s.tau.cross(tau).norm(), 0.0, 1e-12 * tau.norm()) << k;
    ASSERT_GE(s.tau.dot(tau), 0.0) << k;
  }
}

TEST(Saturation, OnlyTheFirstNJointsCount) {
  const Saturated s = saturate(Vec3(4.0, 1e9, 1e9), Vec3(2.0, 0.0, 0.0), 1);
  EXPECT_EQ(s.status, SaturationStatus::kSaturated);
  EXPECT_EQ(s.tau, Vec3(2.0, 0.0, 0.0));
}

TEST(Saturation, NonFiniteInputGivesZero) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Vec3& tau : {Vec3(1.0, nan, 0.0), Vec3(inf, 0.0, 0.0), Vec3(0.0, 0.0, -inf)}) {
    const Saturated s = saturate(tau, Vec3(1.0, 1.0, 1.0), 3);
    EXPECT_EQ(s.status, SaturationStatus::kNonFinite);
    EXPECT_EQ(s.tau, Vec3::Zero());
  }
  EXPECT_EQ(saturate(Vec3(0.1, 0.1, 0.1), Vec3(1.0, nan, 1.0), 3).tau, Vec3::Zero());
  EXPECT_EQ(saturate(Vec3(0.1, 0.1, 0.1), Vec3(1.0, -1.0, 1.0), 3).status,
            SaturationStatus::kNonFinite);
}

}  // namespace
}  // namespace hapticd::kinematics
