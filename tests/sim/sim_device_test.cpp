// The simulated device behind the Device seam: encoder, output gating, tick semantics and the
// RT contract (no allocation).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.h"
#include "config/config.h"
#include "plant_numbers.h"
#include "sim/sim_device.h"

namespace hapticd::sim {
namespace {

using config::OperatorSpec;
using plant_numbers::kNaN;
using plant_numbers::kT;

config::DeviceConfig at_rest(double x0, double counts_per_unit) {
  config::DeviceConfig c;
  c.sim.op.kind = OperatorSpec::Kind::kNone;
  c.sim.initial_position = x0;
  c.sim.counts_per_unit = counts_per_unit;
  return c;
}

double read_position(SimDevice& d) {
  PositionSample s;
  EXPECT_EQ(d.read(s), IoStatus::kOk);
  return s.position;
}

TEST(SimDeviceEncoder, IdealEncoderReportsExactPosition) {
  SimDevice d(at_rest(0.0123456789, 0.0), kT);
  d.configure();
  EXPECT_EQ(read_position(d), 0.0123456789);
  EXPECT_EQ(read_position(d), 0.0123456789);  // at rest, no force
}

TEST(SimDeviceEncoder, QuantisesWithFloor) {
  SimDevice pos(at_rest(1.23456e-3, 1e5), kT);  // 123.456 counts
  pos.configure();
  EXPECT_DOUBLE_EQ(read_position(pos), 123.0 / 1e5);
  SimDevice neg(at_rest(-2.5e-5, 1e5), kT);  // -2.5 counts: floor, not truncation toward 0
  neg.configure();
  EXPECT_DOUBLE_EQ(read_position(neg), -3.0 / 1e5);
}

std::vector<double> noisy_reads(std::uint64_t seed, int n) {
  config::DeviceConfig c = at_rest(1.0e-3 + 0.5e-5, 1e5);
  c.sim.noise_counts = 2.0;
  c.sim.seed = seed;
  SimDevice d(c, kT);
  d.configure();
  std::vector<double> out;
  for (int i = 0; i < n; ++i) out.push_back(read_position(d));
  return out;
}

TEST(SimDeviceEncoder, NoiseIsDeterministicPerSeed) {
  const auto a = noisy_reads(42, 200);
  EXPECT_EQ(a, noisy_reads(42, 200));
  EXPECT_NE(a, noisy_reads(43, 200));
  // The device is at rest, so any spread is the noise; 2 counts std spans several counts.
  const auto [lo, hi] = std::minmax_element(a.begin(), a.end());
  EXPECT_GE(*hi - *lo, 4.0 / 1e5);
  // Seed 0 turns noise off: every read is the quantised rest position (100 counts).
  for (const double x : noisy_reads(0, 50)) EXPECT_DOUBLE_EQ(x, 100.0 / 1e5);
}

TEST(SimDeviceEncoder, ConfigureRestartsTheNoiseSequence) {
  config::DeviceConfig c = at_rest(0.0, 1e5);
  c.sim.noise_counts = 1.5;
  c.sim.seed = 7;
  SimDevice d(c, kT);
  d.configure();
  std::vector<double> first, second;
  for (int i = 0; i < 31; ++i) first.push_back(read_position(d));  // odd: a cached normal
  d.close();
  d.configure();
  for (int i = 0; i < 31; ++i) second.push_back(read_position(d));
  EXPECT_EQ(first, second);
}

TEST(SimDevice, DisabledOutputAppliesZeroForce) {
  SimDevice d(at_rest(0.0, 0.0), kT);
  d.configure();
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(d.write(5.0), IoStatus::kTransportFault) << "refused until enable";
    EXPECT_EQ(read_position(d), 0.0);
  }
  EXPECT_EQ(d.axis().plant().motor_work_j(), 0.0);
  PositionSample s;
  d.read(s);
  EXPECT_EQ(s.status & SimDevice::kStatusOutputEnabled, 0u);

  d.enable();
  for (int i = 0; i < 10; ++i) {
    d.write(5.0);
    d.read(s);
  }
  EXPECT_GT(s.position, 0.0);  // +u pushes toward +x
  EXPECT_NE(s.status & SimDevice::kStatusOutputEnabled, 0u);

  d.disable();
  const double v = d.axis().plant().velocity();
  d.write(5.0);
  d.read(s);
  EXPECT_LT(d.axis().plant().velocity(), v);  // only damping acts now
}

TEST(SimDevice, NonFiniteWriteFaultsAndAppliesZero) {
  SimDevice d(at_rest(0.0, 0.0), kT);
  d.configure();
  d.enable();
  EXPECT_EQ(d.write(2.0), IoStatus::kOk);
  EXPECT_EQ(d.write(std::numeric_limits<double>::quiet_NaN()), IoStatus::kTransportFault);
  EXPECT_EQ(d.state(), DeviceState::kFaulted);
  EXPECT_NE(d.describe_fault().find("non-finite"), std::string::npos) << d.describe_fault();
  EXPECT_EQ(d.axis().held_force(), 0.0);  // zero was applied, not the garbage
  EXPECT_EQ(d.last_command(), 0.0);
  EXPECT_EQ(d.write(1.0), IoStatus::kTransportFault) << "latched: only zero passes";
  EXPECT_EQ(d.axis().held_force(), 0.0);
  d.clear_fault();
  EXPECT_EQ(d.state(), DeviceState::kConfigured);
}

TEST(SimDevice, TheLifecycleRefusesWhatItsStateDoesNotAllow) {
  SimDevice d(at_rest(0.0, 0.0), kT);
  PositionSample s;
  EXPECT_EQ(d.read(s), IoStatus::kTransportFault) << "nothing is open before configure";
  EXPECT_EQ(d.state(), DeviceState::kUnconfigured);
  EXPECT_THROW(d.enable(), DeviceError);
  EXPECT_THROW(d.clear_fault(), DeviceError);
  d.configure();
  EXPECT_THROW(d.configure(), DeviceError);
  EXPECT_EQ(d.write(1.0), IoStatus::kTransportFault) << "output is off until enable";
  EXPECT_EQ(d.axis().held_force(), 0.0);
  d.enable();
  EXPECT_THROW(d.enable(), DeviceError);
  EXPECT_EQ(d.write(1.0), IoStatus::kOk);
  EXPECT_EQ(d.last_command(), 1.0);
  d.close();
  EXPECT_EQ(d.state(), DeviceState::kUnconfigured);
  EXPECT_FALSE(d.axis().output_on());
  EXPECT_EQ(d.last_command(), 0.0);
}

// A device enabled moving at 0.1 m/s from 2 mm, beside the plant it must match step for step.
struct Moving {
  static config::DeviceConfig config() {
    config::DeviceConfig c = at_rest(0.002, 0.0);
    c.sim.initial_velocity = 0.1;
    return c;
  }
  Moving() {
    device.configure();
    device.enable();
  }
  config::DeviceConfig c = config();
  SimDevice device{c, kT};
  Plant ref{c.mass[0], c.damping[0], c.sim.op, kT, 0.002, 0.1};
};

TEST(SimDevice, OneReadIsOnePeriodWithTheLastWrittenForce) {
  Moving m;
  SimDevice& d = m.device;
  Plant& ref = m.ref;
  EXPECT_EQ(read_position(d), ref.position());  // first read: the initial state
  EXPECT_EQ(d.axis().plant().time_s(), 0.0);
  for (int k = 1; k <= 50; ++k) {
    const double u = 0.5 * std::cos(0.3 * k);
    d.write(u);
    ref.step(u);
    EXPECT_EQ(read_position(d), ref.position()) << "tick " << k;
    EXPECT_DOUBLE_EQ(d.axis().plant().time_s(), k * kT);
  }
}

// A loop that skipped periods (a stalled host) says so at its next read: the sim lives through
// them with the force it held, as a real device would, rather than pausing with the loop.
TEST(SimDevice, AReadAfterSkippedPeriodsAdvancesThemAllWithTheHeldForce) {
  Moving m;
  SimDevice& d = m.device;
  Plant& ref = m.ref;
  EXPECT_EQ(read_position(d), ref.position());
  std::uint32_t total = 0;
  for (const std::uint32_t periods : {1u, 4u, 1u, 17u, 2u}) {
    const double u = 0.3 * periods;
    d.write(u);
    for (std::uint32_t k = 0; k < periods; ++k) ref.step(u);
    total += periods;
    PositionSample s;
    ASSERT_EQ(d.read(std::span<PositionSample>(&s, 1), periods), IoStatus::kOk);
    EXPECT_EQ(s.position, ref.position()) << periods << " periods";
    EXPECT_DOUBLE_EQ(d.axis().plant().time_s(), total * kT);
  }
}

// device.mass and damping per joint: each joint of the mechanism moves as its own mass and
// damping make it, the exact step of the one-joint plant with that joint's numbers.
TEST(SimDevice, EachJointOfSeveralMovesWithItsOwnMassAndDamping) {
  config::DeviceConfig c = at_rest(0.0, 0.0);
  c.kinematics.kind = kinematics::Kind::kJoints;
  c.kinematics.joints.n = 3;
  c.mass[0] = 0.1, c.mass[1] = 0.4, c.mass[2] = 0.05;
  c.damping[0] = 2.0, c.damping[1] = 1.0, c.damping[2] = 6.0;
  SimDevice d(c, kT);
  d.configure();
  d.enable();
  std::array<PositionSample, 3> s{};
  ASSERT_EQ(d.read(std::span<PositionSample>(s)), IoStatus::kOk);
  const std::array<double, 3> tau{0.5, -0.25, 1.0};
  std::vector<Plant> ref;
  for (std::size_t i = 0; i < 3; ++i)
    ref.emplace_back(c.mass[i], c.damping[i], c.sim.op, kT, 0.0, 0.0);
  for (int k = 0; k < 20; ++k) {
    d.write(std::span<const double>(tau));
    ASSERT_EQ(d.read(std::span<PositionSample>(s)), IoStatus::kOk);
    for (std::size_t i = 0; i < 3; ++i) {
      ref[i].step(tau[i]);
      EXPECT_NEAR(s[i].position, ref[i].position(), 1e-12) << "joint " << i << " tick " << k;
    }
  }
  EXPECT_GT(std::abs(s[0].position), 2.0 * std::abs(s[1].position)) << "four times the mass";
}

TEST(SimDevice, IdentityAndTransportDelay) {
  SimDevice d(config::DeviceConfig{}, kT);
  d.configure();
  EXPECT_EQ(d.info().transport_delay_samples, 0);
  EXPECT_EQ(d.driver_name(), "sim");
}

TEST(SimDevice, RejectsBadEncoderConfig) {
  config::DeviceConfig c = at_rest(0.0, -1.0);
  EXPECT_THROW(SimDevice(c, kT), std::invalid_argument);
  c = at_rest(0.0, 1e5);
  c.sim.noise_counts = kNaN;
  EXPECT_THROW(SimDevice(c, kT), std::invalid_argument);
}

TEST(SimDevice, NoAllocationOnTheTickPath) {
  // The most demanding configuration: hand with breakpoints inside periods, noisy encoder.
  config::DeviceConfig c;
  c.sim.op.kind = OperatorSpec::Kind::kHand;
  c.sim.op.setpoint.shape = config::ProfileSpec::Shape::kPress;
  c.sim.op.setpoint.points = {{0.00237, 0.0}, {0.00287, 0.01}, {4.5004, 0.01}, {4.5004, 0.0}};
  c.sim.noise_counts = 1.0;
  c.sim.seed = 3;
  SimDevice d(c, kT);
  d.configure();
  d.enable();
  PositionSample s;
  hapticd::testing::AllocationScope scope;
  for (int k = 0; k < 10000; ++k) {
    d.read(s);
    d.write(-100.0 * s.position);
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_DOUBLE_EQ(d.axis().plant().time_s(), 9999 * kT);  // the loop really ran the breakpoints
}

}  // namespace
}  // namespace hapticd::sim
