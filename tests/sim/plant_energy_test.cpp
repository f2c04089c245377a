// Energy bookkeeping, imposed motion, replay and input validation of the plant.
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "config/config.h"
#include "plant_numbers.h"
#include "sim/plant.h"

namespace hapticd::sim {
namespace {

using config::OperatorSpec;
using config::ProfileSpec;
using plant_numbers::kB;
using plant_numbers::kInf;
using plant_numbers::kM;
using plant_numbers::kNaN;
using plant_numbers::kT;
using Kind = OperatorSpec::Kind;

OperatorSpec of_kind(Kind kind) {
  OperatorSpec op;
  op.kind = kind;
  return op;
}

TEST(PlantEnergy, FreeDeviceOperatorDoesNoWork) {
  // f_op = 0, so dKE + integral(b v^2) - integral(u v) must vanish: this checks the Van Loan
  // integral of v^2 against the exact dynamics, with a force that changes every period.
  Plant plant(kM, kB, of_kind(Kind::kNone), kT, 0.0, 0.3);
  for (int k = 0; k < 2000; ++k) plant.step(2.0 * std::sin(0.01 * k) + 0.5);
  ASSERT_GT(plant.dissipated_j(), 1e-3);
  ASSERT_GT(std::abs(plant.motor_work_j()), 1e-3);
  // The terms are ~2 J; each of 2000 steps adds ~1e-16 relative round-off, so 1e-12 of the
  // dissipated energy bounds it. A 1e-6 relative error in the v^2 integral would show as 2e-6.
  EXPECT_NEAR(plant.operator_work_j(), 0.0, 1e-12 * plant.dissipated_j());
}

TEST(PlantEnergy, ConstantForceDoesForceTimesDisplacement) {
  OperatorSpec op = of_kind(Kind::kForce);
  op.force.points = {{0.0, 1.5}};
  const double x0 = 0.004;
  Plant plant(kM, kB, op, kT, x0, -0.1);
  for (int k = 0; k < 500; ++k) plant.step(-0.3);
  const double expected = 1.5 * (plant.position() - x0);
  EXPECT_NEAR(plant.operator_work_j(), expected, 1e-12 * std::abs(expected));
  EXPECT_DOUBLE_EQ(plant.operator_force(), 1.5);
}

TEST(PlantEnergy, BalanceHoldsForHandWithPress) {
  OperatorSpec op = of_kind(Kind::kHand);
  op.setpoint.shape = ProfileSpec::Shape::kPress;
  op.setpoint.points = {{0.0, 0.0}, {0.0137, 0.01}, {0.2, 0.01}, {0.2304, 0.0}};
  Plant plant(kM, kB, op, kT, 0.0, 0.0);
  const double ke0 = plant.kinetic_energy_j();
  for (int k = 0; k < 300; ++k) plant.step(-1.0);
  const double balance =
      plant.kinetic_energy_j() - ke0 + plant.dissipated_j() - plant.motor_work_j();
  EXPECT_NEAR(plant.operator_work_j(), balance, 1e-12 * std::abs(plant.dissipated_j()));
  EXPECT_DOUBLE_EQ(plant.kinetic_energy_j(), 0.5 * kM * plant.velocity() * plant.velocity());
}

OperatorSpec motion_spec() {
  OperatorSpec op = of_kind(Kind::kMotion);
  op.motion.offset = 0.01;
  op.motion.amplitude = 0.004;
  op.motion.frequency_hz = 10.0;  // 100 samples per motion period
  op.motion.phase_rad = 0.2;
  return op;
}

double cosine_at(const config::MotionSpec& m, int k) {
  const double t = k * kT;
  return m.offset + m.amplitude * std::cos(2 * std::numbers::pi * m.frequency_hz * t + m.phase_rad);
}

TEST(PlantImposedMotion, PositionsAtInstantsAreTheCosine) {
  const OperatorSpec op = motion_spec();
  Plant plant(kM, kB, op, kT, 123.0, 456.0);  // x0, v0 ignored: the motion is imposed
  EXPECT_DOUBLE_EQ(plant.position(), cosine_at(op.motion, 0));
  for (int k = 1; k <= 250; ++k) {
    plant.step(0.3);
    ASSERT_DOUBLE_EQ(plant.position(), cosine_at(op.motion, k)) << "step " << k;
    const double v = (cosine_at(op.motion, k) - cosine_at(op.motion, k - 1)) / kT;
    ASSERT_NEAR(plant.velocity(), v, 1e-12);
    // No acceleration inside a period: the operator balances damping and motor.
    ASSERT_NEAR(plant.operator_force(), kB * v - 0.3, 1e-12);
  }
}

TEST(PlantImposedMotion, WorkOverOnePeriodIsDampingLossOnly) {
  for (const double u : {0.0, 0.7}) {
    const OperatorSpec op = motion_spec();
    Plant plant(kM, kB, op, kT, 0.0, 0.0);
    plant.step(u);  // measure from instant 1, over the 100 periods of one motion cycle
    const double w1 = plant.operator_work_j();
    double sum_v2 = 0.0;
    for (int k = 1; k <= 100; ++k) {
      const double v = (cosine_at(op.motion, k + 1) - cosine_at(op.motion, k)) / kT;
      sum_v2 += v * v;
      plant.step(u);
    }
    // dKE = 0 and the motor's u dx sums to u (x_101 - x_1) = 0 over a cycle; what is left
    // is b sum(v_k^2) T (~1e-4 J), up to round-off in positions of ~1e-18 m.
    EXPECT_NEAR(plant.operator_work_j() - w1, kB * sum_v2 * kT, 1e-12) << "u = " << u;
    EXPECT_GT(sum_v2, 0.0);
  }
}

TEST(PlantImposedMotion, ImpulseAtVelocityJumpIsCountedInKineticEnergy) {
  // Replay 0 -> 1 mm in one period, then hold: the operator gives the mass v = 1 m/s, then
  // stops it. Net work = damping loss of the moving period only, KE back to zero.
  Plant plant(kM, kB, of_kind(Kind::kReplay), kT, 0.0, 0.0, {0.0, 0.001});
  EXPECT_DOUBLE_EQ(plant.velocity(), 1.0);  // starts on the trajectory
  plant.step(0.0);
  plant.step(0.0);
  EXPECT_DOUBLE_EQ(plant.velocity(), 0.0);
  EXPECT_DOUBLE_EQ(plant.kinetic_energy_j(), 0.0);
  EXPECT_NEAR(plant.operator_work_j(), kB * 1.0 * kT - 0.5 * kM * 1.0, 1e-15);
}

TEST(PlantReplay, FollowsPositionsThenHolds) {
  const std::vector<double> pos = {0.0, 0.001, 0.003, 0.0025};
  Plant plant(kM, kB, of_kind(Kind::kReplay), kT, 9.0, 9.0, pos);
  EXPECT_EQ(plant.position(), pos[0]);
  for (std::size_t k = 1; k < 10; ++k) {
    plant.step(0.0);
    const double expected = k < pos.size() ? pos[k] : pos.back();
    EXPECT_EQ(plant.position(), expected) << "step " << k;
    if (k >= pos.size()) {
      EXPECT_EQ(plant.velocity(), 0.0);
    }
  }
}

TEST(PlantReset, ReturnsToTheInitialState) {
  OperatorSpec op = of_kind(Kind::kHand);
  op.setpoint.points = {{0.00037, 0.0}, {0.00037, 0.01}};
  Plant plant(kM, kB, op, kT, 0.001, 0.0);
  std::vector<double> first;
  for (int k = 0; k < 20; ++k) {
    plant.step(0.1);
    first.push_back(plant.position());
  }
  plant.reset();
  EXPECT_EQ(plant.time_s(), 0.0);
  EXPECT_EQ(plant.operator_work_j(), 0.0);
  EXPECT_EQ(plant.position(), 0.001);
  for (int k = 0; k < 20; ++k) {
    plant.step(0.1);
    EXPECT_EQ(plant.position(), first[static_cast<std::size_t>(k)]) << "step " << k;
  }
}

void expect_invalid(const std::function<void()>& f, const std::string& fragment) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one mentioning '" << fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(PlantValidation, RejectsBadInputWithAClearMessage) {
  const OperatorSpec none = of_kind(Kind::kNone);
  expect_invalid([&] { Plant(kM, kB, of_kind(Kind::kReplay), kT, 0, 0); }, "at least one");
  expect_invalid([&] { Plant(kM, kB, none, kT, 0, 0, {1.0}); }, "not a replay");
  expect_invalid([&] { Plant(0.0, kB, none, kT, 0, 0); }, "mass");
  expect_invalid([&] { Plant(kM, -1.0, none, kT, 0, 0); }, "damping");
  expect_invalid([&] { Plant(kM, kB, none, 0.0, 0, 0); }, "sample period");
  expect_invalid([&] { Plant(kM, kB, none, kT, kNaN, 0); }, "initial");
  OperatorSpec hand = of_kind(Kind::kHand);
  hand.setpoint.points = {{0.2, 0.0}, {0.1, 1.0}};
  expect_invalid([&] { Plant(kM, kB, hand, kT, 0, 0); }, "times must not decrease");
  hand.setpoint.points = {};
  hand.stiffness = -1.0;
  expect_invalid([&] { Plant(kM, kB, hand, kT, 0, 0); }, "hand stiffness");
  expect_invalid(
      [&] {
        Plant(kM, kB, of_kind(Kind::kReplay), kT, 0, 0, {0.0, kInf});
      },
      "replay position 1");
}

}  // namespace
}  // namespace hapticd::sim
