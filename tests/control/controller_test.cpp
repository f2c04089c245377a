// The contact law against sequences computed by hand from docs/math.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "alloc_counter.h"
#include "control/controller.h"

namespace hapticd::control {
namespace {

// docs/math.md's law as written: these tests start inside the wall on purpose, so the
// start-up arming (tested on its own below) is off.
ControlLaw pure_law(const config::Config& c) {
  ControlLaw law = make_control_law(c);
  law.require_outside_start = false;
  return law;
}

config::Config wall(double k, double b,
                    config::Discretization disc = config::Discretization::kBackward) {
  config::Config c;
  c.loop.rate_hz = 1000.0;  // T = 1 ms
  c.wall.stiffness = k;
  c.wall.damping = b;
  c.wall.discretization = disc;
  c.device.max_force = 1e9;
  return c;
}

TEST(Controller, BackwardWallIsKXiPlusBDifferenceOfXi) {
  Controller ctl(pure_law(wall(1000, 0.5)));
  // x: outside, enters 1 mm, 3 mm, back to 2 mm, leaves.
  const std::vector<double> x{-0.001, 0.001, 0.003, 0.002, -0.0005, -0.001};
  const std::vector<double> xi{0, 0.001, 0.003, 0.002, 0, 0};
  double prev = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const ControlOutput o = ctl.step(x[k]);
    const double f = 1000 * xi[k] + 0.5 * (xi[k] - prev) / 1e-3;
    prev = xi[k];
    EXPECT_NEAR(o.force_computed, f, 1e-12) << "k=" << k;
    EXPECT_NEAR(o.force_commanded, -f, 1e-12) << "k=" << k;  // n = +1: u = -f
    EXPECT_EQ((o.flags & kControlContact) != 0, xi[k] > 0) << "k=" << k;
    EXPECT_DOUBLE_EQ(o.penetration, x[k]);
  }
}

// Issue 7: `std::abs(u) > max_force` let a NaN through, and copysign would have turned it
// into full force. A non-finite force must command nothing and say so.
TEST(Controller, ANonFiniteForceIsNeverCommanded) {
  for (const double bad :
       {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    ControlLaw law = pure_law(wall(1000, 0.5));
    law.environment.num[0] = bad;
    law.e0 = bad;
    Controller ctl(law);
    const ControlOutput o = ctl.step(0.001);
    EXPECT_FALSE(std::isfinite(o.force_computed));
    EXPECT_EQ(o.force_commanded, 0.0);
    EXPECT_TRUE(o.flags & kControlNonFinite);
    EXPECT_FALSE(o.flags & kControlSaturated);
  }
}

TEST(Controller, ReleaseStepPullsUnlessNoPull) {
  // Leaving contact, the damping term -B xi_{k-1}/T pulls toward the wall; no_pull clamps it.
  config::Config c = wall(1000, 0.5);
  Controller pulls(pure_law(c));
  pulls.step(0.002);
  const ControlOutput released = pulls.step(-0.001);
  EXPECT_NEAR(released.force_computed, -0.5 * 0.002 / 1e-3, 1e-12);
  EXPECT_NEAR(released.force_commanded, 1.0, 1e-12);

  c.wall.no_pull = true;
  Controller clamped(pure_law(c));
  clamped.step(0.002);
  const ControlOutput o = clamped.step(-0.001);
  EXPECT_NEAR(o.force_computed, -1.0, 1e-12);  // the law is unchanged...
  EXPECT_EQ(o.force_commanded, 0.0);           // ...only the command is clamped
  EXPECT_TRUE(o.flags & kControlNoPullClamped);
}

TEST(Controller, TustinWallIsTheBilinearRecursion) {
  Controller ctl(pure_law(wall(1000, 0.5, config::Discretization::kTustin)));
  const std::vector<double> x{0.0, 0.001, 0.0025, 0.002, -0.001, -0.002};
  double f_prev = 0.0, xi_prev = 0.0;
  const double a = 1000 + 2 * 0.5 / 1e-3, b = 1000 - 2 * 0.5 / 1e-3;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double xi = std::max(x[k], 0.0);
    const double f = -f_prev + a * xi + b * xi_prev;  // (1 + z^-1) f = (a + b z^-1) xi
    EXPECT_NEAR(ctl.step(x[k]).force_computed, f, 1e-9) << "k=" << k;
    f_prev = f;
    xi_prev = xi;
  }
}

TEST(Controller, DelayCommandsTheForceComputedDSamplesEarlier) {
  config::Config c = wall(1000, 0.0);
  c.wall.delay_samples = 2;
  Controller ctl(pure_law(c));
  const std::vector<double> x{0.001, 0.002, 0.003, 0.004, 0.005};
  for (std::size_t k = 0; k < x.size(); ++k) {
    const ControlOutput o = ctl.step(x[k]);
    EXPECT_NEAR(o.force_computed, 1000 * x[k], 1e-12);
    EXPECT_NEAR(o.force_commanded, k < 2 ? 0.0 : -1000 * x[k - 2], 1e-12) << "k=" << k;
  }
}

TEST(Controller, NormalAndWallPositionSetPenetrationAndForceDirection) {
  config::Config c = wall(1000, 0.0);
  c.wall.position = 0.05;
  c.wall.normal = -1;  // wall occupies x < 0.05
  Controller ctl(pure_law(c));
  const ControlOutput out = ctl.step(0.06);  // 10 mm on the free side
  EXPECT_NEAR(out.penetration, -0.01, 1e-15);
  EXPECT_EQ(out.force_commanded, 0.0);
  const ControlOutput in = ctl.step(0.048);  // 2 mm inside
  EXPECT_NEAR(in.penetration, 0.002, 1e-15);
  EXPECT_NEAR(in.force_commanded, +2.0, 1e-12);  // pushes toward +x, out of the wall
}

TEST(Controller, SaturatesToMaxForceKeepingTheSign) {
  config::Config c = wall(1000, 0.0);
  c.device.max_force = 1.5;
  Controller ctl(pure_law(c));
  const ControlOutput o = ctl.step(0.004);
  EXPECT_NEAR(o.force_computed, 4.0, 1e-12);
  EXPECT_EQ(o.force_commanded, -1.5);
  EXPECT_TRUE(o.flags & kControlSaturated);
  EXPECT_FALSE(ctl.step(0.001).flags & kControlSaturated);
}

TEST(Controller, VelocityIsTheBackwardDifference) {
  Controller ctl(pure_law(wall(0, 0)));
  EXPECT_EQ(ctl.step(0.010).velocity, 0.0);  // no previous sample yet
  EXPECT_NEAR(ctl.step(0.012).velocity, 2.0, 1e-12);
}

TEST(Controller, ResetForgetsHistory) {
  Controller ctl(pure_law(wall(1000, 0.5)));
  ctl.step(0.003);
  ctl.reset();
  EXPECT_NEAR(ctl.step(0.001).force_computed, 1000 * 0.001 + 0.5 * 0.001 / 1e-3, 1e-12);
}

TEST(Controller, StepDoesNotAllocate) {
  config::Config c = wall(2000, 0.2);
  c.wall.delay_samples = 3;
  c.wall.coupling = {true, {0.1, -0.0752, 0.0016, -0.0101}, {1, -1.8407, 0.8444, -0.0037}};
  Controller ctl(pure_law(c));
  testing::AllocationScope scope;
  double sink = 0.0;
  for (int k = 0; k < 20000; ++k) sink += ctl.step(0.001 * ((k % 7) - 3)).force_commanded;
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(Controller, StartingInsideTheWallIsUnarmedUntilTheDeviceLeaves) {
  Controller ctl(make_control_law(wall(1000, 0.5)));
  for (double x : {0.003, 0.002}) {  // started 3 mm inside: no K p0 + B p0/T kick
    const ControlOutput o = ctl.step(x);
    EXPECT_EQ(o.force_commanded, 0.0);
    EXPECT_TRUE(o.flags & kControlUnarmed);
    EXPECT_FALSE(o.flags & kControlContact);
  }
  const ControlOutput left = ctl.step(-0.001);
  EXPECT_EQ(left.force_commanded, 0.0);
  EXPECT_FALSE(left.flags & kControlUnarmed);
  // Back in: the law runs from a history that was outside the wall.
  EXPECT_NEAR(ctl.step(0.001).force_computed, 1000 * 0.001 + 0.5 * 0.001 / 1e-3, 1e-12);
}

TEST(Controller, ArmsAtOnceWhenStartingOutside) {
  Controller ctl(make_control_law(wall(1000, 0.0)));
  ctl.step(-0.001);
  EXPECT_NEAR(ctl.step(0.002).force_commanded, -2.0, 1e-12);
}

TEST(ControlLaw, RejectsNegativeCouplingFeedThrough) {
  config::Config c = wall(1000, 0.0);
  c.wall.coupling = {true, {-0.1}, {1.0}};
  EXPECT_THROW(make_control_law(c), std::invalid_argument);
}

}  // namespace
}  // namespace hapticd::control

#include "config/config_loader.h"
#include "control/derived_check.h"

namespace hapticd::control {
namespace {

std::vector<std::string> derived_errors(const config::Config& c) {
  try {
    check_derived_quantities(c);
  } catch (const config::ConfigError& e) {
    return e.messages();
  }
  return {};
}

// Issue 7: each key was in range, but what the controller and the gate derive from them was
// not a finite number, and the gate passed.
TEST(DerivedQuantities, OverflowsAreNamedAtTheKeyToChange) {
  config::Config c = wall(2000, 0.2);
  c.source_name = "t.yaml";
  EXPECT_TRUE(derived_errors(c).empty());

  c.wall.damping = 1e306;
  EXPECT_EQ(derived_errors(c),
            std::vector<std::string>{"t.yaml: wall.damping: makes the wall filter E(z) overflow "
                                     "(B/T is not a finite number at T = 0.001 s)"});
  c.wall.damping = 0.2;
  c.wall.coupling = {true, {1e200}, {1e-200}};
  EXPECT_EQ(derived_errors(c),
            std::vector<std::string>{"t.yaml: wall.coupling: coefficients divided by "
                                     "denominator[0] overflow: C(z) is not a finite filter"});
  c.wall.coupling = {true, {1e306, 1.0}, {1.0, 0.5}};  // finite C, but 1 + E C overflows
  ASSERT_EQ(derived_errors(c).size(), 1u);
  EXPECT_NE(derived_errors(c)[0].find("wall.coupling: the contact map"), std::string::npos);
}

}  // namespace
}  // namespace hapticd::control

namespace hapticd::control {
namespace {

// Issue 32, the runaway guard: K 2000 N/m, max_force 10 N, so the bound is 1.5 x 5 mm.
config::Config guarded() {
  config::Config c = wall(2000, 0.0);
  c.device.max_force = 10.0;
  return c;
}

// Steps `ctl` through positions; whether any step set kControlRunaway, and at which one.
int first_runaway(Controller& ctl, const std::vector<double>& x) {
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (ctl.step(x[k]).flags & kControlRunaway) return static_cast<int>(k);
  }
  return -1;
}

std::vector<double> motion(double x0, double v0, double a, int ticks) {
  std::vector<double> x;
  for (int k = 0; k < ticks; ++k) {
    const double t = k * 1e-3;
    x.push_back(x0 + v0 * t + 0.5 * a * t * t);
  }
  return x;
}

TEST(RunawayGuard, TheBoundIsOneAndAHalfTimesWhereTheWallSaturatesOrTheConfiguredOne) {
  EXPECT_DOUBLE_EQ(runaway_penetration(guarded()), 0.0075);
  config::Config c = guarded();
  c.safety.max_penetration = 0.02;
  EXPECT_DOUBLE_EQ(runaway_penetration(c), 0.02);
  c = guarded();
  c.wall.stiffness = 0.0;  // a pure damper holds no position: only a configured bound
  EXPECT_TRUE(std::isinf(runaway_penetration(c)));
}

TEST(RunawayGuard, ADevicePulledInFaultsAsItPassesTheBound) {
  Controller ctl(make_control_law(guarded()));
  // From outside, accelerating into the wall (a wall that pulls: 100 m/s^2).
  const std::vector<double> x = motion(-0.001, 0.0, 100.0, 30);
  const int k = first_runaway(ctl, x);
  ASSERT_GE(k, 0);
  EXPECT_GT(x[k], 0.0075);
  EXPECT_LT(x[k - 1], 0.0075) << "at the first tick past the bound";
}

TEST(RunawayGuard, AHardImpactTheWallIsBrakingPassesTheBoundAndIsLetBe) {
  Controller ctl(make_control_law(guarded()));
  // From outside in at 1 m/s, braked at 100 m/s^2 by the saturated wall: past 7.5 mm and back.
  std::vector<double> x = motion(-0.002, 1.0, 0.0, 8);
  const std::vector<double> brake = motion(x.back() + 1e-3, 1.0, -100.0, 25);
  x.insert(x.end(), brake.begin(), brake.end());
  EXPECT_GT(*std::max_element(x.begin(), x.end()), 0.0075);
  EXPECT_EQ(first_runaway(ctl, x), -1);
}

TEST(RunawayGuard, ADevicePinnedBeyondTheBoundFaults) {
  Controller ctl(make_control_law(guarded()));
  // From outside in at 1 m/s to 9 mm, then held there.
  std::vector<double> x = motion(-0.001, 1.0, 0.0, 11);
  x.insert(x.end(), 10, x.back());
  EXPECT_GE(first_runaway(ctl, x), 0);
}

TEST(RunawayGuard, DeepButNotSaturatedIsNoRunaway) {
  config::Config c = guarded();
  c.safety.max_penetration = 0.001;  // below where the wall saturates: never at the limit there
  Controller ctl(make_control_law(c));
  const std::vector<double> x = motion(-0.001, 0.0, 20.0, 20);  // to 2.6 mm: 5.2 N
  EXPECT_GT(x.back(), 0.001);
  EXPECT_EQ(first_runaway(ctl, x), -1);
}

}  // namespace
}  // namespace hapticd::control
