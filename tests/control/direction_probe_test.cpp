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
  // A hand moving it to and fro on top: amplitude (m), frequency (Hz), phase (rad).
  double wobble = 0.0, wobble_hz = 1.0, wobble_phase = 0.0;
  int delay = 0;
  double period = kT;    // the loop's sample period (s)
  double quantum = 0.0;  // encoder count (m); 0: exact
  double noise = 0.0;    // Gaussian noise (m)
  double lost = 0.0;     // share of commands a congested link loses (the last one stays)
  // An encoder whose reading moves at most one count every `slow_counts` ticks (edges spaced
  // out, as a GPIO line the kernel delivers late): it follows the motion, behind it.
  int slow_counts = 0;
  double shown = 0.0;
  int since_count = 0;
  double x = 0.0, v = 0.0, t = 0.0;
  std::vector<double> pending;
  std::mt19937_64 rng{7};

  double read() {
    double y = x + drift * t + wobble * std::sin(2.0 * M_PI * wobble_hz * t + wobble_phase);
    if (noise > 0.0) y += std::normal_distribution<double>(0.0, noise)(rng);
    if (quantum > 0.0) y = std::floor(y / quantum) * quantum;
    if (slow_counts > 0 && ++since_count >= slow_counts && y != shown) {
      shown += y > shown ? quantum : -quantum;
      since_count = 0;
    }
    return slow_counts > 0 ? shown : y;
  }
  void write(double u) {
    if (lost > 0.0 && !pending.empty() && std::uniform_real_distribution<double>()(rng) < lost) {
      u = pending.back();  // this command never arrived: the device holds the last one
    }
    pending.push_back(u);
    const double acting = pending.size() > static_cast<std::size_t>(delay)
                              ? pending[pending.size() - 1 - delay]
                              : 0.0;
    const int steps = 200;
    const double h = period / steps;
    for (int i = 0; i < steps; ++i) {
      const double f = sign * acting - (damping + hand_damping) * v - hand_stiffness * (x - rest);
      v += f / mass * h;
      x += v * h;
    }
    t += period;
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

// One push, never the other way, then the device's response awaited (declared delay 0 and the
// default 50 ms more), then, confirmed, the brake that stops the model's device.
TEST(DirectionProbe, ItPushesOutOfTheWallWaitsForTheMotionThenBrakesAndEndsAtZero) {
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
    EXPECT_EQ(p.max_delay, 50);
    for (int j = 0; j < 25; ++j) EXPECT_EQ(written[start + j], p.force);
    for (int j = 25; j < 75; ++j) EXPECT_EQ(written[start + j], 0.0) << "waiting, at " << j;
    EXPECT_NEAR(p.brake, std::exp(-0.075 * 2.0 / 0.1), 1e-12) << "exp(-(n + D) T b / m)";
    ASSERT_EQ(written.size(), start + 100);
    for (int j = 75; j < 100; ++j) EXPECT_EQ(written[start + j], -p.brake * p.force);
    for (const double u : written) EXPECT_LE(u * p.force, p.force * p.force) << "never more";
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
// ... whatever the hand and however much later than declared the device answers (up to the
// latency the check allows).
TEST(DirectionProbe, NoHandEverTurnsTheVerdictAround) {
  for (const int late : {0, 3, 12, 50}) {
    for (const double k : {0.0, 30.0, 300.0, 1e3, 3e3, 1e4, 1e5}) {
      for (const double bh : {0.0, 5.0, 50.0}) {
        for (const double sign : {1.0, -1.0}) {
          Device d;
          d.sign = sign;
          d.delay = late;  // declared: 0
          d.hand_stiffness = k;
          d.hand_damping = bh;
          d.quantum = 1e-6;
          DirectionProbe probe(probe_plan(demo(), 0));
          const ProbeResult r = run(probe, d);
          SCOPED_TRACE("late " + std::to_string(late) + " k " + std::to_string(k) + " b_h " +
                       std::to_string(bh));
          EXPECT_NE(r.state, sign > 0 ? ProbeState::kReversed : ProbeState::kConfirmed) << r.gain;
          if (k <= 1e3 && bh <= 5.0) {
            EXPECT_EQ(r.state, sign > 0 ? ProbeState::kConfirmed : ProbeState::kReversed) << r.gain;
            // The delay is found by the model's shape, which a stiff hand changes.
            if (k <= 300.0) {
              EXPECT_NEAR(r.latency, late, 2) << "the delay the motion came with";
            }
          }
        }
      }
    }
  }
}

// A congested link (a USB queue that fills, an emulated controller that stalls) loses commands
// and delivers the rest late: what reaches the device is less push, later, never a push the
// other way, so the verdict's sign holds.
TEST(DirectionProbe, ALinkThatLosesAndDelaysCommandsNeverTurnsTheVerdictAround) {
  for (int seed = 0; seed < 40; ++seed) {
    for (const double sign : {1.0, -1.0}) {
      Device d;
      d.sign = sign;
      d.rng.seed(static_cast<std::uint64_t>(seed));
      d.lost = 0.6;
      d.delay = seed % 30;
      d.hand_stiffness = seed % 2 ? 300.0 : 0.0;
      d.hand_damping = 5.0;
      d.quantum = 1e-5;
      const ProbeResult r = run(demo(), d);
      SCOPED_TRACE("seed " + std::to_string(seed));
      EXPECT_NE(r.state, sign > 0 ? ProbeState::kReversed : ProbeState::kConfirmed) << r.gain;
    }
  }
}

// A hand moving the device to and fro while the check runs (the check waits for it to be
// still, and a turning point of the motion is still for a moment): whatever the motion's size,
// pace and phase, a force as commanded is never called reversed, nor a reversed one confirmed.
TEST(DirectionProbe, AHandMovingTheDeviceNeverTurnsTheVerdictAround) {
  for (const double amplitude : {0.001, 0.003, 0.01, 0.03}) {
    for (const double hz : {0.5, 1.0, 3.0, 8.0}) {
      for (int phase = 0; phase < 8; ++phase) {
        for (const double sign : {1.0, -1.0}) {
          Device d;
          d.sign = sign;
          d.wobble = amplitude;
          d.wobble_hz = hz;
          d.wobble_phase = phase * M_PI / 4.0;
          d.quantum = 1e-5;
          const ProbeResult r = run(demo(), d);
          SCOPED_TRACE("amplitude " + std::to_string(amplitude) + " Hz " + std::to_string(hz) +
                       " phase " + std::to_string(phase));
          EXPECT_NE(r.state, sign > 0 ? ProbeState::kReversed : ProbeState::kConfirmed) << r.gain;
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

// A coarse encoder that can only follow the push's motion behind it (one count every few
// ticks): its steps come late and few, and a fit whose baseline could bend to take them up
// saw the hand's return as motion against the push. Never reversed; confirmed when it shows.
TEST(DirectionProbe, AnEncoderSlowerThanThePushNeverTurnsTheVerdictAround) {
  config::Config cfg = demo();  // 50 Hz, its transport allowed 300 ms: a GPIO device's rig
  cfg.loop.rate_hz = 50;
  cfg.safety.direction_check.max_latency_ms = 300;
  for (const int slow : {1, 2, 4, 8}) {
    for (const double k : {0.0, 300.0, 1e3}) {
      for (const double sign : {1.0, -1.0}) {
        Device d;
        d.period = 0.02;
        d.sign = sign;
        d.quantum = 5e-4;  // 0.5 mm counts
        d.slow_counts = slow;
        d.hand_stiffness = k;
        d.hand_damping = 5.0;
        const ProbeResult r = run(cfg, d);
        SCOPED_TRACE("a count every " + std::to_string(slow) + " ticks, hand " + std::to_string(k) +
                     " N/m");
        EXPECT_NE(r.state, sign > 0 ? ProbeState::kReversed : ProbeState::kConfirmed) << r.gain;
        if (r.gain_error > 0.0 && std::abs(r.gain) > 4.0 * r.gain_error) {
          EXPECT_GT(r.gain * sign, 0.0) << "a significant fit has the push's sign";
        }
        if (slow == 1 && k <= 300.0) {
          EXPECT_EQ(r.state, sign > 0 ? ProbeState::kConfirmed : ProbeState::kReversed) << r.gain;
        }
      }
    }
  }
}

// Runs the probe on the device with the loop skipping periods: tick k comes `periods(k)`
// periods after tick k - 1, the device holding the last force over them. The forces written.
template <typename Periods>
std::vector<double> run_skipping(DirectionProbe& probe, Device& d, Periods periods) {
  std::vector<double> written;
  std::uint32_t p = 1;
  for (int k = 0; k < 10000 && !probe.ended(); ++k) {
    written.push_back(probe.step(d.read(), p));
    p = periods(k + 1);
    for (std::uint32_t i = 0; i < p; ++i) d.write(written.back());
  }
  return written;
}

// A loaded host stalls the loop every few ticks (CI's sanitizer run of the demo: an overrun
// every 12 ticks, 280 periods skipped in 1000): the device held the force over them, so the
// pulse is followed in periods, and the verdict and the gain are the same as without.
TEST(DirectionProbe, ALoopThatSkipsPeriodsStillFindsTheWayAndHowMuch) {
  for (const double sign : {1.0, -1.0}) {
    for (const int every : {5, 7, 12, 31}) {
      DirectionProbe probe(probe_plan(demo(), 0));
      Device d;
      d.sign = sign;
      const bool hand = every % 2 == 1;
      d.hand_stiffness = hand ? 300.0 : 0.0;  // the demo's hand, or none
      d.hand_damping = hand ? 5.0 : 0.0;
      const Device held_only = d;
      run_skipping(probe, d, [&](int k) { return k % every == 0 ? 1u + k % 5 : 1u; });
      const ProbeResult r = probe.result();
      Device steady = held_only;
      const ProbeResult ref = run(demo(), steady);
      EXPECT_EQ(r.state, sign > 0 ? ProbeState::kConfirmed : ProbeState::kReversed)
          << "every " << every;
      EXPECT_NEAR(r.gain, ref.gain, 0.05) << "every " << every;
      EXPECT_LT(r.ticks, 400u) << "no push given up: every " << every;
      if (sign > 0 && !hand) {
        EXPECT_LT(std::abs(d.v), 1e-3) << "the brake stops it: every " << every;
      }
    }
  }
}

// A stall at the push's end held the force longer: a longer push, which the model has too; one
// held past twice its length is given up (zero at once) and the check pushes again from rest.
TEST(DirectionProbe, APushAStallLengthensIsFittedAsLongerOrGivenUpWhenTooLong) {
  const ProbePlan p = probe_plan(demo(), 0);
  const std::size_t start = static_cast<std::size_t>(p.rest_ticks) - 1;
  for (const std::uint32_t stall : {10u, 40u}) {
    DirectionProbe probe(p);
    Device d;
    const auto written = run_skipping(probe, d, [&](int k) {
      return static_cast<std::size_t>(k) == start + 20 ? stall : 1u;  // from period 19 on
    });
    EXPECT_EQ(probe.result().state, ProbeState::kConfirmed) << stall;
    // Pushed again from near rest, the first push's glide still dying away: a little more.
    EXPECT_NEAR(probe.result().gain, 1.0, stall == 10u ? 0.05 : 0.1) << stall;
    EXPECT_EQ(written[start + 20], 0.0) << "the push ended when the loop came back";
    int pushes = 0;
    for (std::size_t k = 1; k < written.size(); ++k) {
      pushes += written[k] == p.force && written[k - 1] != p.force;
    }
    EXPECT_EQ(pushes, stall == 10u ? 1 : 2) << "19 + 10 <= 2n: fitted; 19 + 40: pushed again";
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
  EXPECT_EQ(p.max_delay, 1 + 5) << "the declared delay, and 50 ms more";
  EXPECT_EQ(p.window(), static_cast<std::size_t>(p.rest_ticks + 3 + p.max_delay));
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
