// Every fault the loop detects: zero force is commanded at once, the loop stops and says why.
#include <gtest/gtest.h>

#include <cmath>
#include <ctime>
#include <limits>

#include "control/controller.h"
#include "freerun.h"
#include "loop/servo_loop.h"
#include "scripted_device.h"

namespace hapticd::loop {
namespace {

using hapticd::testing::ScriptedDevice;

control::Controller wall_controller() {
  config::Config c;
  c.wall.stiffness = 2000;
  c.device.max_force = 10;
  control::ControlLaw law = control::make_control_law(c);
  law.require_outside_start = false;  // the scripted device starts 1 mm inside on purpose
  return control::Controller(law);
}

LoopResult run(ScriptedDevice& dev, LoopOptions o) {
  control::Controller ctl = wall_controller();
  ServoLoop loop(dev, ctl, nullptr, o);
  const std::atomic<bool> stop{false};
  return loop.run(stop);
}

// Issue 7: only the sim device's own finiteness check stopped a NaN force; the loop must fault
// and command zero whatever the device does with it.
TEST(LoopFaults, NonFiniteForceFaultsAndCommandsZero) {
  ScriptedDevice dev;
  config::Config c;
  c.wall.stiffness = 2000;
  c.device.max_force = 10;
  control::ControlLaw law = control::make_control_law(c);
  law.require_outside_start = false;
  law.environment.num[0] = std::numeric_limits<double>::quiet_NaN();
  law.e0 = law.environment.num[0];
  law.delay_samples = 0;
  control::Controller ctl(law);
  ServoLoop loop(dev, ctl, nullptr, freerun());
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  EXPECT_EQ(r.fault.cause, FaultCause::kNonFiniteForce);
  EXPECT_EQ(r.fault.tick, 0u);
  EXPECT_EQ(r.ticks, 1u);
  ASSERT_FALSE(dev.writes.empty());
  for (double w : dev.writes) EXPECT_EQ(w, 0.0);
  EXPECT_NE(describe(r.fault).find("non-finite force"), std::string::npos);
}

TEST(LoopFaults, DeviceReadErrorFaultsAndCommandsZero) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = 0.001;
    return k == 5 ? IoStatus::kTransportFault : IoStatus::kOk;
  };
  const LoopResult r = run(dev, freerun());
  EXPECT_EQ(r.fault.cause, FaultCause::kTransportRead);
  EXPECT_EQ(r.fault.tick, 5u);
  EXPECT_EQ(r.ticks, 6u);
  ASSERT_GE(dev.writes.size(), 6u);
  EXPECT_NEAR(dev.writes[4], -2.0, 1e-12);  // the wall was pushing before the fault
  EXPECT_EQ(dev.writes[5], 0.0);            // the faulted tick itself commands zero
  EXPECT_EQ(dev.writes.back(), 0.0);
  EXPECT_EQ(describe(r.fault), "transport fault reading the device at tick 5");
}

TEST(LoopFaults, StaleDataFaultsAfterTheConfiguredStreak) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = 0.001;
    return k >= 10 ? IoStatus::kNoNewData : IoStatus::kOk;
  };
  LoopOptions o = freerun();
  o.sample.stale_fault_ticks = 4;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kStaleData);
  EXPECT_EQ(r.fault.tick, 13u);
  EXPECT_EQ(r.count(loop::kCounterStaleTicks), 4u);
  EXPECT_EQ(dev.writes.back(), 0.0);
  // Until the streak ran out, the held position kept the wall pushing.
  EXPECT_NEAR(dev.writes[12], -2.0, 1e-12);
}

TEST(LoopFaults, AnIsolatedStaleReadIsCountedNotFatal) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = 0.001;
    return k % 10 == 3 ? IoStatus::kNoNewData : IoStatus::kOk;
  };
  const LoopResult r = run(dev, freerun(100));
  EXPECT_EQ(r.fault.cause, FaultCause::kNone);
  EXPECT_EQ(r.count(loop::kCounterStaleTicks), 10u);
}

TEST(LoopFaults, NonFinitePositionFaults) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = k == 7 ? std::numeric_limits<double>::quiet_NaN() : 0.001;
    return IoStatus::kOk;
  };
  const LoopResult r = run(dev, freerun());
  EXPECT_EQ(r.fault.cause, FaultCause::kNonFinitePosition);
  EXPECT_EQ(r.fault.tick, 7u);
  EXPECT_EQ(dev.writes.back(), 0.0);
}

TEST(LoopFaults, EncoderJumpFasterThanMaxSpeedFaults) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = k < 20 ? 0.001 : 0.031;  // 30 mm in one 1 ms period: 30 m/s
    return IoStatus::kOk;
  };
  LoopOptions o = freerun();
  o.sample.max_speed = 10.0;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kEncoderJump);
  EXPECT_EQ(r.fault.tick, 20u);
  EXPECT_NEAR(r.fault.value, 30.0, 1e-9);
  EXPECT_EQ(dev.writes.back(), 0.0);
}

TEST(LoopFaults, DeviceWriteErrorFaultsAndRetriesZero) {
  ScriptedDevice dev;
  dev.fail_write_at = 3;
  const LoopResult r = run(dev, freerun());
  EXPECT_EQ(r.fault.cause, FaultCause::kTransportWrite);
  EXPECT_EQ(r.fault.tick, 3u);
  EXPECT_EQ(dev.writes.back(), 0.0);
}

TEST(LoopFaults, OverrunStreakFaults) {
  ScriptedDevice dev;
  dev.read_sleep_ns = 2'000'000;  // every read outlasts a 0.5 ms period, whatever the host
  LoopOptions o;
  o.sample.realtime = true;
  o.sample.period_ns = 500'000;
  o.overrun_fault_streak = 3;
  o.max_ticks = 50;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kOverrunStreak);
  EXPECT_EQ(r.fault.tick, 2u);
  EXPECT_EQ(r.count(loop::kCounterOverruns), 3u);
  EXPECT_EQ(dev.writes.back(), 0.0);
}

TEST(LoopFaults, LongOverrunsSkipWholePeriodsAndCountThem) {
  ScriptedDevice dev;
  dev.read_sleep_ns = 2'000'000;
  LoopOptions o;
  o.sample.realtime = true;
  o.sample.period_ns = 500'000;
  o.overrun_fault_streak = 1000;
  o.max_ticks = 5;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kNone);
  EXPECT_EQ(r.count(loop::kCounterOverruns), r.ticks);
  EXPECT_GE(r.count(loop::kCounterMissedTicks),
            2u * r.ticks);  // each 2 ms tick spans 4 periods, 3 skipped
}

TEST(LoopFaults, ANormalEndAlsoLeavesZeroForce) {
  ScriptedDevice dev;  // 1 mm inside the wall: the last command pushed
  const LoopResult r = run(dev, freerun(10));
  EXPECT_EQ(r.fault.cause, FaultCause::kNone);
  ASSERT_EQ(dev.writes.size(), 11u);
  EXPECT_NEAR(dev.writes[9], -2.0, 1e-12);
  EXPECT_EQ(dev.writes[10], 0.0);  // written after the last tick, before run() returns
}

TEST(LoopFaults, NothingIsCommandedBeforeTheFirstPosition) {
  // Wall at -10 mm, device at -20 mm: outside. A stale first read must not be taken as x = 0
  // (10 mm inside) and pushed on.
  config::Config c;
  c.wall.position = -0.010;
  c.wall.stiffness = 2000;
  c.device.max_force = 100;
  control::Controller ctl(control::make_control_law(c));
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = -0.020;
    return k < 2 ? IoStatus::kNoNewData : IoStatus::kOk;
  };
  ServoLoop loop(dev, ctl, nullptr, freerun(5));
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  EXPECT_EQ(r.fault.cause, FaultCause::kNone);
  EXPECT_EQ(r.count(loop::kCounterContactTicks), 0u);
  for (double f : dev.writes) EXPECT_EQ(f, 0.0);
}

// Found in the GPIO kernel runs: one encoder count between two samples whose edge times were
// 48 us apart read as 10 m/s and faulted the run. The samples' times may lengthen the span a
// jump is judged over, never shorten it below the periods that passed.
TEST(LoopFaults, OneCountBetweenEdgesMicrosecondsApartIsNoImpossibleSpeed) {
  ScriptedDevice dev;
  std::int64_t last_edge = 0;
  dev.script = [&](std::uint64_t k, PositionSample& s) {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    // Until tick 10 an edge just now; then one count more, 20 us after the previous edge.
    last_edge = k == 10 ? last_edge + 20'000 : now.tv_sec * 1'000'000'000LL + now.tv_nsec;
    s.position = k < 10 ? 0.0 : 0.0005;  // 0.5 mm: 25 m/s over 20 us, 0.5 m/s over 1 ms
    s.time_ns = last_edge;
    s.flags |= kSampleHasTime;
    return IoStatus::kOk;
  };
  LoopOptions o;
  o.sample.realtime = true;
  o.sample.period_ns = 1'000'000;
  o.max_ticks = 15;
  o.overrun_fault_streak = 1000;  // the host may be slow; only the speed judgement is tested
  o.sample.stale_fault_ticks = 1000;
  o.sample.max_speed = 10.0;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kNone) << r.fault.value;
  EXPECT_EQ(r.ticks, 15u);
}

TEST(LoopFaults, AJumpAfterStaleReadsIsJudgedOverTheTimeThatPassed) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    // 25 mm out of the wall (inside it, deeper than the wall holds, the runaway guard would
    // fault), arriving after two stale reads: 3 periods.
    s.position = k < 7 ? 0.0 : -0.025;
    return (k == 5 || k == 6) ? IoStatus::kNoNewData : IoStatus::kOk;
  };
  LoopOptions o = freerun(10);
  o.sample.max_speed = 10.0;  // 25 mm / 3 ms = 8.3 m/s: plausible
  EXPECT_EQ(run(dev, o).fault.cause, FaultCause::kNone);
}

// Issue 22: a device four times faster than the loop hands the driver four reports a tick; it
// keeps the newest and says it took in four. Nothing was lost: no gap, no fault.
TEST(LoopFaults, ReportsReplacedWithinATickAreNoSequenceGap) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = 0.001;
    s.sequence = (4 * k + 3) % 256;  // an 8-bit counter: wraps every 64 ticks
    s.samples = 4;
    s.flags = kSampleHasSequence;
    return IoStatus::kOk;
  };
  LoopOptions o = freerun(200);
  o.sample.sequence_gap_fault = 1;
  o.sample.sequence_modulus = 256;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kNone) << r.fault.value;
  EXPECT_EQ(r.count(loop::kCounterSequenceGaps), 0u);
  EXPECT_EQ(r.count(loop::kCounterSamplesMissed), 0u);
}

// ... while a device that really skips samples still faults: four taken in, six numbered.
TEST(LoopFaults, ADeviceThatSkipsSamplesBeyondThoseTakenInStillFaults) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = 0.001;
    s.sequence = k < 10 ? 4 * k : 4 * k + 2;  // tick 10: two numbers nobody received
    s.samples = 4;
    s.flags = kSampleHasSequence;
    return IoStatus::kOk;
  };
  LoopOptions o = freerun(100);
  o.sample.sequence_gap_fault = 2;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kSequenceGap);
  EXPECT_EQ(r.fault.tick, 10u);
  EXPECT_EQ(r.fault.value, 2.0);
  EXPECT_EQ(r.count(loop::kCounterSamplesMissed), 2u);
}

// Issue 22: a device that reports on change says nothing while the axis rests; the driver
// hands the loop its last position, marked held. Not stale, and the move the next report
// shows is judged over the whole time since the last report, not one period.
TEST(LoopFaults, HeldPositionsAreNotStaleAndTheNextMoveIsJudgedOverTheirTime) {
  ScriptedDevice dev;
  dev.script = [](std::uint64_t k, PositionSample& s) {
    s.position = k < 60 ? 0.0 : -0.025;  // 25 mm out of the wall after 50 held ticks: 0.5 m/s
    s.flags = k >= 10 && k < 60 ? kSampleHeld : 0;
    return IoStatus::kOk;
  };
  LoopOptions o = freerun(70);
  o.sample.max_speed = 10.0;  // 25 mm in one period would be 25 m/s
  o.sample.stale_fault_ticks = 3;
  const LoopResult r = run(dev, o);
  EXPECT_EQ(r.fault.cause, FaultCause::kNone) << describe(r.fault);
  EXPECT_EQ(r.count(loop::kCounterStaleTicks), 0u);
  EXPECT_EQ(r.ticks, 70u);
}

}  // namespace
}  // namespace hapticd::loop
