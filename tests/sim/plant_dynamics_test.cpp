// The plant's state at the sample instants against closed forms and an independent RK4
// reference: the step must be the exact discretisation, breakpoints inside a period included.
#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "config/config.h"
#include "plant_numbers.h"
#include "reference.h"
#include "sim/plant.h"

namespace hapticd::sim {
namespace {

using config::OperatorSpec;
using config::ProfileSpec;
using plant_numbers::kB;
using plant_numbers::kM;
using plant_numbers::kT;
using Points = std::vector<std::pair<double, double>>;

ProfileSpec press(const Points& pts) {
  ProfileSpec p;
  p.shape = ProfileSpec::Shape::kPress;
  for (const auto& [t, v] : pts) p.points.push_back({t, v});
  return p;
}

// Largest |a_i - b_i| over the instants, for x and v separately.
struct Errors {
  double x = 0.0;
  double v = 0.0;
};

TEST(PlantDynamics, FreeMassDamperMatchesClosedForm) {
  OperatorSpec op;
  op.kind = OperatorSpec::Kind::kNone;
  const double x0 = 0.01, v0 = -0.2, u = 3.0;
  Plant plant(kM, kB, op, kT, x0, v0);
  const double tau = kM / kB;  // 50 ms: 3000 steps cover the transient and the ramp
  for (int k = 1; k <= 3000; ++k) {
    plant.step(u);
    const double t = k * kT;
    const double decay = -std::expm1(-t / tau);  // 1 - e^{-bt/m} without cancellation
    const double x = x0 + (v0 - u / kB) * tau * decay + (u / kB) * t;
    const double v = u / kB + (v0 - u / kB) * std::exp(-t / tau);
    // Only round-off separates the two: 1e-12 relative leaves room for ~10^4 roundings.
    ASSERT_NEAR(plant.position(), x, 1e-12 * std::abs(x)) << "step " << k;
    ASSERT_NEAR(plant.velocity(), v, 1e-12 * (std::abs(v0) + u / kB)) << "step " << k;
    ASSERT_DOUBLE_EQ(plant.time_s(), t);
  }
}

TEST(PlantDynamics, ForceStepAtThirtySevenPercentOfThePeriodActsForTheRest) {
  // A 1 N force switched on at 0.37 T: from rest the device feels it for exactly 0.63 T of
  // the first period, v = (F/b)(1 - e^{-(b/m)(t - t0)}). Snapping the step to either sample
  // instant would change v(T) by ~37% or ~63%.
  OperatorSpec op;
  op.kind = OperatorSpec::Kind::kForce;
  const double t0 = 0.37 * kT, f = 1.0;
  op.force = press({{t0, 0.0}, {t0, f}});
  Plant plant(kM, kB, op, kT, 0.0, 0.0);
  for (int k = 1; k <= 20; ++k) {
    plant.step(0.0);
    const double dt = k * kT - t0;
    const double e = -std::expm1(-kB / kM * dt);
    const double v = f / kB * e;
    const double x = f / kB * (dt - kM / kB * e);
    ASSERT_NEAR(plant.velocity(), v, 1e-13 * f / kB) << "step " << k;
    ASSERT_NEAR(plant.position(), x, 1e-13 * std::abs(x) + 1e-20) << "step " << k;
  }
}

// The hand operator with a time-varying motor force, compared with RK4 at every instant.
Errors hand_errors(const ProfileSpec& setpoint, const Points& ref_points,
                   const std::function<double(double)>& ref_smooth, int steps, double* work_err,
                   double* work_scale) {
  OperatorSpec op;
  op.kind = OperatorSpec::Kind::kHand;
  op.stiffness = 300.0;
  op.damping = 5.0;
  op.setpoint = setpoint;
  const double x0 = 0.002, v0 = 0.05;
  Plant plant(kM, kB, op, kT, x0, v0);
  std::vector<double> u;
  for (int k = 0; k < steps; ++k) u.push_back(0.4 * std::sin(0.05 * k));

  const testref::Params p{kM, kB, true, op.stiffness, op.damping};
  // RK4 with h = T/1000: |lambda h| < 1e-4 for these poles (|lambda| ~ 55/s), so truncation
  // (~(lambda h)^4 per unit time) is far below round-off.
  const auto ref = testref::simulate(p, {x0, v0, 0.0}, kT, u, ref_points, ref_smooth, kT / 1000);
  Errors e;
  double wmax = 0.0;
  for (int k = 0; k < steps; ++k) {
    plant.step(u[static_cast<std::size_t>(k)]);
    const auto& r = ref[static_cast<std::size_t>(k) + 1];
    e.x = std::max(e.x, std::abs(plant.position() - r.x));
    e.v = std::max(e.v, std::abs(plant.velocity() - r.v));
    wmax = std::max(wmax, std::abs(r.w));
  }
  *work_err = std::abs(plant.operator_work_j() - ref.back().w);
  *work_scale = wmax;
  return e;
}

TEST(PlantDynamics, HandWithSineSetpointMatchesReference) {
  ProfileSpec s;
  s.shape = ProfileSpec::Shape::kSine;
  s.offset = 0.01;
  s.amplitude = 0.005;
  s.frequency_hz = 7.0;
  s.phase_rad = 0.3;
  const double w = 2 * std::numbers::pi * s.frequency_hz;
  double werr = 0.0, wscale = 0.0;
  const Errors e = hand_errors(
      s, {}, [&](double t) { return s.offset + s.amplitude * std::sin(w * t + s.phase_rad); }, 400,
      &werr, &wscale);
  // Positions are ~1e-2 m and velocities ~0.5 m/s; 3e5 RK4 steps accumulate round-off of
  // order 1e-14 relative. 1e-11 relative is a tight bound that a wrong generator or ZOH
  // (errors of order 1e-3 and more) cannot meet.
  EXPECT_LT(e.x, 1e-13);
  EXPECT_LT(e.v, 1e-11);
  // The exact Van Loan work against RK4's quadrature of f_op v (observed ~1e-13 relative).
  EXPECT_LT(werr, 1e-11 * wscale);
  EXPECT_GT(wscale, 1e-4);  // the comparison is not of two zeros
}

// A press: ramp starting at 2.37 T, two knots inside period 2, a jump at 6.37 T, a ramp down
// ending mid-period, then hold.
const Points kPress = {{2.37 * kT, 0.0},   {2.87 * kT, 0.02},  {6.37 * kT, 0.02},
                       {6.37 * kT, 0.005}, {9.1 * kT, -0.004}, {12.55 * kT, 0.0}};

TEST(PlantDynamics, HandWithPressProfileHonoursBreakpointsInsidePeriods) {
  double werr = 0.0, wscale = 0.0;
  const Errors e = hand_errors(press(kPress), kPress, nullptr, 60, &werr, &wscale);
  EXPECT_LT(e.x, 1e-13);  // same reasoning as the sine case; fewer steps
  EXPECT_LT(e.v, 1e-11);
  EXPECT_LT(werr, 1e-11 * wscale);

  // The tolerance discriminates: the same press with its knots snapped to the preceding
  // sample instants (what a step-wise, non-splitting simulator does) differs by far more.
  Points snapped;
  for (const auto& [t, v] : kPress) snapped.push_back({std::floor(t / kT) * kT, v});
  double serr = 0.0, sscale = 0.0;
  const Errors s = hand_errors(press(kPress), snapped, nullptr, 60, &serr, &sscale);
  EXPECT_GT(s.x, 1e-7);
  EXPECT_GT(s.v, 1e-5);
}

TEST(PlantDynamics, PressWithoutMotorForceAndWithBreakpointsOnInstants) {
  // Breakpoints exactly on sample instants (3 T, 7 T) take the on-instant path: no split, the
  // generator is re-anchored with the new value and slope at that instant.
  const Points pts = {{3 * kT, 0.0}, {7 * kT, 0.01}, {7 * kT, 0.0}};
  OperatorSpec op;
  op.kind = OperatorSpec::Kind::kForce;
  op.force = press(pts);
  Plant plant(kM, kB, op, kT, 0.0, 0.0);
  const testref::Params p{kM, kB, false, 0.0, 0.0};
  const std::vector<double> u(15, 0.0);
  const auto ref = testref::simulate(p, {}, kT, u, pts, nullptr, kT / 1000);
  for (std::size_t k = 0; k < u.size(); ++k) {
    plant.step(0.0);
    EXPECT_NEAR(plant.velocity(), ref[k + 1].v, 1e-14) << "step " << k;  // v ~ 1e-4 m/s
    // The profile value at the instant, right-continuous: the jump back to 0 shows at 7 T.
    const double n = static_cast<double>(k + 1);
    const double expected = (n >= 3 && n < 7) ? 0.01 * (n - 3) / 4 : 0.0;
    EXPECT_NEAR(plant.operator_force(), expected, 1e-15) << "step " << k;
  }
}

}  // namespace
}  // namespace hapticd::sim
