// The direction check's probe against a device simulated here (finely integrated, not the
// probe's own ZOH model): a force as commanded is confirmed, a reversed one refused, a device
// held firmly or never still is neither, and the verdict survives what real devices add (a
// hand's spring, a transport delay, a coarse or noisy encoder, a slow drift).
#include "control/direction_probe.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "alloc_counter.h"

namespace hapticd::control {
namespace {

constexpr double kT = 0.001;

config::Config demo() {
  config::Config c;  // the defaults: 1 kHz, m 0.1 kg, b 2 N s/m, max_force 10 N, check on
  c.wall.normal = 1;
  return c;
}

// m x'' = sign u - b x' - k (x - rest) - b_h x' + push, integrated in 200 steps a tick; the
// force written at tick k acts over the period from tick k + delay.
struct Device {
  double mass = 0.1, damping = 2.0, sign = 1.0;
  double hand_stiffness = 0.0, hand_damping = 0.0, rest = 0.0;
  double drift = 0.0;  // m/s of motion imposed on top (a hand moving it slowly)
  int delay = 0;
  double quantum = 0.0;  // encoder count (m); 0: exact
  double noise = 0.0;    // Gaussian noise (m)
  double x = 0.0, v = 0.0, t = 0.0;
  std::vector<double> pending;
  std::mt19937_64 rng{7};

  double read() {
    double y = x + drift * t;
    if (noise > 0.0) y += std::normal_distribution<double>(0.0, noise)(rng);
    if (quantum > 0.0) y = std::floor(y / quantum) * quantum;
    return y;
  }
  void write(double u) {
    pending.push_back(u);
    const double acting = pending.size() > static_cast<std::size_t>(delay)
                              ? pending[pending.size() - 1 - delay]
                              : 0.0;
    const int steps = 200;
    const double h = kT / steps;
    for (int i = 0; i < steps; ++i) {
      const double f = sign * acting - (damping + hand_damping) * v - hand_stiffness * (x - rest);
      v += f / mass * h;
      x += v * h;
    }
    t += kT;
  }
};

// Runs the probe on the device until it ends (or 10 s); the result.
ProbeResult run(DirectionProbe& probe, Device& d) {
  for (int k = 0; k < 10000 && !probe.ended(); ++k) d.write(probe.step(d.read()));
  return probe.result();
}

ProbeResult run(const config::Config& cfg, Device d) {
  DirectionProbe probe(probe_plan(cfg, d.delay));
  return run(probe, d);
}

TEST(DirectionProbe, AFreeDevicePushedAsCommandedIsConfirmedWithAGainNearOne) {
  const ProbeResult r = run(demo(), Device{});
  EXPECT_EQ(r.state, ProbeState::kConfirmed) << r.gain;
  EXPECT_NEAR(r.gain, 1.0, 0.05);
  EXPECT_LT(r.gain_error, 0.01);
  EXPECT_LT(r.ticks, 200u) << "at rest at once: the rest window and the pulse";
}

TEST(DirectionProbe, AReversedForceIsFoundReversed) {
  Device d;
  d.sign = -1.0;
  const ProbeResult r = run(demo(), d);
  EXPECT_EQ(r.state, ProbeState::kReversed);
  EXPECT_NEAR(r.gain, -1.0, 0.05);
}

TEST(DirectionProbe, ItPushesOutOfTheWallFirstThenBrakesAndEndsAtZero) {
  for (const int normal : {1, -1}) {
    config::Config c = demo();
    c.wall.normal = normal;
    const ProbePlan p = probe_plan(c, 0);
    EXPECT_DOUBLE_EQ(p.force, -normal * 0.05 * 10.0) << "5 % of max_force, along -n";
    EXPECT_EQ(p.half_ticks, 25) << "25 ms at 1 kHz";
    DirectionProbe probe(p);
    Device d;
    std::vector<double> written;
    for (int k = 0; k < 1000 && !probe.ended(); ++k) {
      written.push_back(probe.step(d.read()));
      d.write(written.back());
    }
    ASSERT_EQ(probe.result().state, ProbeState::kConfirmed);
    const std::size_t start = static_cast<std::size_t>(p.rest_ticks) - 1;
    for (int j = 0; j < 25; ++j) EXPECT_EQ(written[start + j], p.force);
    EXPECT_NEAR(p.brake, std::exp(-0.025 * 2.0 / 0.1), 1e-12) << "exp(-n T b / m)";
    for (int j = 25; j < 50; ++j) EXPECT_EQ(written[start + j], -p.brake * p.force);
    for (std::size_t k = start + 50; k < written.size(); ++k) EXPECT_EQ(written[k], 0.0);
    EXPECT_LT(std::abs(d.v), 1e-3) << "the brake stops the device again";
  }
}

TEST(DirectionProbe, AHandResistingItStillLetsItConfirm) {
  Device d;
  d.hand_stiffness = 300.0;  // the demo's hand
  d.hand_damping = 5.0;
  const ProbeResult r = run(demo(), d);
  EXPECT_EQ(r.state, ProbeState::kConfirmed) << r.gain;
  EXPECT_GT(r.gain, 0.2);
  EXPECT_LT(r.gain, 1.0);
  d.sign = -1.0;
  EXPECT_EQ(run(demo(), d).state, ProbeState::kReversed);
}

// The safety property: however stiff and damped the hand holding it, a force as commanded is
// never called reversed and a reversed one never confirmed (from rest, a mass on a spring and a
// damper moves the way it is pushed first; only later does the spring pull it back).
TEST(DirectionProbe, NoHandEverTurnsTheVerdictAround) {
  for (const double k : {0.0, 30.0, 300.0, 1e3, 3e3, 1e4, 1e5}) {
    for (const double bh : {0.0, 5.0, 50.0}) {
      for (const double sign : {1.0, -1.0}) {
        Device d;
        d.sign = sign;
        d.hand_stiffness = k;
        d.hand_damping = bh;
        d.quantum = 1e-6;
        const ProbeResult r = run(demo(), d);
        SCOPED_TRACE("k " + std::to_string(k) + " b_h " + std::to_string(bh));
        EXPECT_NE(r.state, sign > 0 ? ProbeState::kReversed : ProbeState::kConfirmed) << r.gain;
        if (k <= 1e3 && bh <= 5.0) {
          EXPECT_EQ(r.state, sign > 0 ? ProbeState::kConfirmed : ProbeState::kReversed) << r.gain;
        }
      }
    }
  }
}

TEST(DirectionProbe, ADeviceHeldFirmlyIsNoMotionEitherWay) {
  for (const double sign : {1.0, -1.0}) {
    Device d;
    d.sign = sign;
    d.hand_stiffness = 3e5;  // a grip a thousand times the demo hand's
    d.hand_damping = 500.0;
    d.quantum = 1e-5;
    const ProbeResult r = run(demo(), d);
    EXPECT_EQ(r.state, ProbeState::kNoMotion) << r.gain;
  }
}

TEST(DirectionProbe, ADelayedTransportACoarseNoisyEncoderAndADriftDoNotFoolIt) {
  for (const double sign : {1.0, -1.0}) {
    Device d;
    d.sign = sign;
    d.delay = 3;
    d.quantum = 1e-5;  // 10 um counts: the pulse moves about 3 mm
    d.noise = 3e-5;    // three counts of noise
    d.drift = 2e-3;    // 2 mm/s
    const ProbeResult r = run(demo(), d);
    EXPECT_EQ(r.state, sign > 0 ? ProbeState::kConfirmed : ProbeState::kReversed) << r.gain;
    EXPECT_NEAR(r.gain, sign, 0.15);
  }
}

TEST(DirectionProbe, ADeviceThatIsNeverStillGivesUpAfterTheTimeOut) {
  config::Config c = demo();
  c.safety.direction_check.rest_timeout_ms = 300;
  DirectionProbe probe(probe_plan(c, 0));
  Device d;
  d.drift = 0.5;  // half a metre a second: never at rest
  const ProbeResult r = run(probe, d);
  EXPECT_EQ(r.state, ProbeState::kNeverAtRest);
  EXPECT_EQ(r.ticks, 300u);
}

TEST(DirectionProbe, OffIsEndedAtOnceAndCommandsNothing) {
  config::Config c = demo();
  c.safety.direction_check.mode = config::DirectionCheckMode::kOff;
  DirectionProbe probe(probe_plan(c, 0));
  EXPECT_TRUE(probe.ended());
  EXPECT_EQ(probe.result().state, ProbeState::kOff);
  EXPECT_EQ(probe.step(0.0), 0.0);
}

TEST(DirectionProbe, AShortPulseAtALowRateStillHasThreeTicksAHalf) {
  config::Config c = demo();
  c.loop.rate_hz = 100.0;  // the kernel test machine's rate
  c.device.mass = 0.05;
  c.device.damping = 0.05;
  const ProbePlan p = probe_plan(c, 1);
  EXPECT_EQ(p.half_ticks, 3);
  EXPECT_EQ(p.window(), static_cast<std::size_t>(p.rest_ticks + 3 * 3 + 1));
}

TEST(DirectionProbe, RestartingChecksAgainAndTheStepNeverAllocates) {
  DirectionProbe probe(probe_plan(demo(), 0));
  Device d;
  run(probe, d);
  ASSERT_EQ(probe.result().state, ProbeState::kConfirmed);
  probe.restart();
  EXPECT_EQ(probe.result().state, ProbeState::kWaiting);
  Device again;
  again.sign = -1.0;
  again.pending.reserve(2000);  // the simulated device's own history: allocated before
  const testing::AllocationScope scope;
  for (int k = 0; k < 1000 && !probe.ended(); ++k) again.write(probe.step(again.read()));
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(probe.result().state, ProbeState::kReversed);
}

}  // namespace
}  // namespace hapticd::control
