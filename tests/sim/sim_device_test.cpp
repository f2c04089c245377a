// The simulated device behind the Device seam: encoder, output gating, tick semantics and the
// RT contract (no allocation).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.h"
#include "config/config.h"
#include "sim/sim_device.h"

namespace hapticd::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using config::OperatorSpec;

constexpr double kT = 1e-3;

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
  d.configure();
  for (int i = 0; i < 31; ++i) second.push_back(read_position(d));
  EXPECT_EQ(first, second);
}

TEST(SimDevice, DisabledOutputAppliesZeroForce) {
  SimDevice d(at_rest(0.0, 0.0), kT);
  d.configure();
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(d.write(5.0), IoStatus::kOk);
    EXPECT_EQ(read_position(d), 0.0);
  }
  EXPECT_EQ(d.plant().motor_work_j(), 0.0);
  PositionSample s;
  d.read(s);
  EXPECT_EQ(s.device_status & SimDevice::kStatusOutputEnabled, 0u);

  d.enable_output();
  for (int i = 0; i < 10; ++i) {
    d.write(5.0);
    d.read(s);
  }
  EXPECT_GT(s.position, 0.0);  // +u pushes toward +x
  EXPECT_NE(s.device_status & SimDevice::kStatusOutputEnabled, 0u);

  d.disable_output();
  const double v = d.plant().velocity();
  d.write(5.0);
  d.read(s);
  EXPECT_LT(d.plant().velocity(), v);  // only damping acts now
}

TEST(SimDevice, NonFiniteWriteIsAnError) {
  SimDevice d(at_rest(0.0, 0.0), kT);
  d.configure();
  d.enable_output();
  EXPECT_EQ(d.write(std::numeric_limits<double>::quiet_NaN()), IoStatus::kError);
  EXPECT_NE(d.describe_error().find("non-finite"), std::string::npos) << d.describe_error();
  EXPECT_EQ(d.write(-std::numeric_limits<double>::infinity()), IoStatus::kError);
  PositionSample s;
  d.read(s);
  d.read(s);
  EXPECT_EQ(d.plant().velocity(), 0.0);  // zero was applied, not the garbage
  EXPECT_EQ(d.write(1.0), IoStatus::kOk);
}

TEST(SimDevice, ReadBeforeConfigureIsAnError) {
  SimDevice d(at_rest(0.0, 0.0), kT);
  PositionSample s;
  EXPECT_EQ(d.read(s), IoStatus::kError);
  EXPECT_NE(d.describe_error().find("configure"), std::string::npos);
  EXPECT_THROW(d.enable_output(), DeviceError);
}

TEST(SimDevice, OneReadIsOnePeriodWithTheLastWrittenForce) {
  config::DeviceConfig c = at_rest(0.002, 0.0);
  c.sim.initial_velocity = 0.1;
  SimDevice d(c, kT);
  d.configure();
  d.enable_output();
  Plant ref(c.mass, c.damping, c.sim.op, kT, 0.002, 0.1);
  EXPECT_EQ(read_position(d), ref.position());  // first read: the initial state
  EXPECT_EQ(d.plant().time_s(), 0.0);
  for (int k = 1; k <= 50; ++k) {
    const double u = 0.5 * std::cos(0.3 * k);
    d.write(u);
    ref.step(u);
    EXPECT_EQ(read_position(d), ref.position()) << "tick " << k;
    EXPECT_DOUBLE_EQ(d.plant().time_s(), k * kT);
  }
}

TEST(SimDevice, IdentityAndTransportDelay) {
  SimDevice d(config::DeviceConfig{}, kT);
  EXPECT_EQ(d.transport_delay_samples(), 0);
  EXPECT_EQ(d.name(), "sim");
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
  d.enable_output();
  PositionSample s;
  hapticd::testing::AllocationScope scope;
  for (int k = 0; k < 10000; ++k) {
    d.read(s);
    d.write(-100.0 * s.position);
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_DOUBLE_EQ(d.plant().time_s(), 9999 * kT);  // the loop really ran the breakpoints
}

}  // namespace
}  // namespace hapticd::sim
