#include <gtest/gtest.h>

#include <cmath>

#include "analysis/passivity.h"
#include "analysis/wall_model.h"

namespace hapticd::analysis {
namespace {

auto backward_family(double b, double t) {
  return [=](double k) { return environment_filter({k, b, t, WallDiscretization::kBackward}); };
}

TEST(MaxStiffness, MatchesClosedFormWithoutDelay) {
  const double t = 1e-3, b_wall = 0.2, available = 1.8;
  const StiffnessLimit lim = max_stiffness(backward_family(b_wall, t), t, 0, 0.0, available);
  ASSERT_EQ(lim.kind, StiffnessLimit::Kind::kBounded);
  EXPECT_NEAR(lim.value, 2 * (available - b_wall) / t, 1e-9 * lim.value);
}

TEST(MaxStiffness, RoundTripsThroughRequiredDamping) {
  const double t = 1e-3;
  for (int delay : {0, 1, 2, 3}) {
    for (double eta : {0.0, 0.3}) {
      const double available = 2.5;
      const StiffnessLimit lim = max_stiffness(backward_family(0.3, t), t, delay, eta, available);
      ASSERT_EQ(lim.kind, StiffnessLimit::Kind::kBounded) << "delay " << delay;
      const double at_limit =
          passivity_bound(backward_family(0.3, t)(lim.value), t, delay, eta).required_damping;
      EXPECT_NEAR(at_limit, available, 1e-9 * available) << "delay " << delay << " eta " << eta;
      // Just above the limit the wall must fail.
      EXPECT_GT(passivity_bound(backward_family(0.3, t)(lim.value * (1 + 1e-6)), t, delay, eta)
                    .required_damping,
                available);
    }
  }
}

TEST(MaxStiffness, NoneWhenTheWallDampingAloneNeedsMore) {
  // Naghshtabrizi & Hespanha's Example 1 bare wall: B = 20 > b = 10, no stiffness passes.
  const StiffnessLimit lim = max_stiffness(backward_family(20.0, 0.02), 0.02, 0, 0.0, 10.0);
  EXPECT_EQ(lim.kind, StiffnessLimit::Kind::kNone);
}

TEST(MaxStiffness, UnboundedBehindTheExampleCoupling) {
  const TransferFunction c{{0.1, -0.0752, 0.0016, -0.0101}, {1, -1.8407, 0.8444, -0.0037}};
  const auto family = [&](double k) {
    return contact_map(environment_filter({k, 20.0, 0.02, WallDiscretization::kBackward}), c);
  };
  const StiffnessLimit lim = max_stiffness(family, 0.02, 0, 0.0, 10.0);
  EXPECT_EQ(lim.kind, StiffnessLimit::Kind::kUnbounded);
  EXPECT_GT(lim.value, 1e15);
}

}  // namespace
}  // namespace hapticd::analysis
