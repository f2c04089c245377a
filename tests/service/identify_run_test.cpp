// identify's tick loop on the in-process sim device: a realtime run allocates nothing and
// records every tick; every way it ends leaves zero force written and output off.
#include "service/commands/identify_run.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "loop/servo_loop.h"
#include "scripted_device.h"
#include "sim/sim_device.h"

namespace hapticd::service {
namespace {

struct IdentifyRig {
  IdentifyRig() : cfg(free_device()), device(cfg.device, cfg.loop.sample_period_s()) {
    device.configure();
    device.enable();
  }
  static config::Config free_device() {
    config::Config c = config::load_embedded_default();
    c.device.sim.op.kind = config::OperatorSpec::Kind::kNone;
    return c;
  }
  config::Config cfg;
  sim::SimDevice device;
};

std::vector<double> sine(std::size_t n, double amplitude) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = amplitude * std::sin(0.05 * static_cast<double>(k));
  return u;
}

ExcitationLimits limits(bool realtime, double max_travel) {
  ExcitationLimits l;
  l.samples.realtime = realtime;
  l.samples.period_ns = 1'000'000;
  l.max_travel = max_travel;
  return l;
}

void expect_safe_end(const IdentifyRig& rig) {
  EXPECT_EQ(rig.device.last_command(), 0.0);
  EXPECT_FALSE(rig.device.output_enabled());
}

TEST(IdentifyRun, RealtimeRecordsEveryTickWithoutAllocating) {
  IdentifyRig rig;
  const std::vector<double> u = sine(200, 1.0);
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{false};
  hapticd::testing::AllocationScope scope;
  run_excitation(rig.device, u, limits(true, 0.1), stop, rec);
  EXPECT_EQ(scope.count(), 0u) << "the tick loop allocated";
  EXPECT_EQ(rec.end, ExcitationEnd::kDone);
  EXPECT_EQ(rec.ticks, 200u);
  EXPECT_EQ(rec.start[0], -0.02);
  EXPECT_GT(rec.travel(), 0.0);
  expect_safe_end(rig);
}

TEST(IdentifyRun, TheTravelGuardEndsItAtZeroForce) {
  IdentifyRig rig;
  const std::vector<double> u(2000, 5.0);  // a steady push: the device runs away
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{false};
  run_excitation(rig.device, u, limits(false, 0.005), stop, rec);
  EXPECT_EQ(rec.end, ExcitationEnd::kTravel);
  EXPECT_LT(rec.ticks, 2000u);
  EXPECT_LE(rec.travel(), 0.005);
  expect_safe_end(rig);
}

TEST(IdentifyRun, AStopEndsItAtZeroForce) {
  IdentifyRig rig;
  const std::vector<double> u = sine(100, 1.0);
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{true};
  run_excitation(rig.device, u, limits(false, 0.1), stop, rec);
  EXPECT_EQ(rec.end, ExcitationEnd::kStopped);
  EXPECT_EQ(rec.ticks, 0u);
  expect_safe_end(rig);
}

TEST(IdentifyRun, ANonFiniteCommandFaultsTheDeviceAndEndsIt) {
  IdentifyRig rig;
  std::vector<double> u = sine(100, 1.0);
  u[40] = std::numeric_limits<double>::quiet_NaN();  // the device refuses it: zero written, fault
                                                     // latched
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{false};
  run_excitation(rig.device, u, limits(false, 0.1), stop, rec);
  EXPECT_EQ(rec.end, ExcitationEnd::kFault);
  EXPECT_EQ(rec.fault.cause, loop::FaultCause::kTransportWrite);
  EXPECT_EQ(rec.ticks, 40u);
  EXPECT_EQ(rig.device.last_command(), 0.0);
  EXPECT_EQ(rig.device.state(), DeviceState::kFaulted);
}

// Issue 24: identify applies every safety check a run applies, because both call the loop's
// SampleCheck and Schedule. Each misbehaving device below faults `hapticd run`'s loop and the
// excitation with the same cause at the same tick, with zero force written last.
struct Misbehaviour {
  const char* name;
  std::function<IoStatus(std::uint64_t, PositionSample&)> script;
  loop::FaultCause cause;
  std::uint64_t tick;
};

std::vector<Misbehaviour> misbehaviours() {
  using C = loop::FaultCause;
  const auto at = [](std::uint64_t k, double x) {  // a well-behaved encoder until tick k
    return [k, x](std::uint64_t t, PositionSample& s) {
      s.position = t < k ? 0.0 : x;
      s.flags = kSampleHasSequence;
      s.sequence = t;
      return IoStatus::kOk;
    };
  };
  return {
      {"stale",
       [](std::uint64_t t, PositionSample& s) {
         s.position = 0.0;
         return t < 10 ? IoStatus::kOk : IoStatus::kNoNewData;
       },
       C::kStaleData, 14},  // safety.stale_fault_ticks 5 below
      {"sequence gap",
       [](std::uint64_t t, PositionSample& s) {
         s.position = 0.0;
         s.flags = kSampleHasSequence;
         s.sequence = t < 20 ? t : t + 3;
         return IoStatus::kOk;
       },
       C::kSequenceGap, 20},
      {"non-finite", at(30, std::numeric_limits<double>::quiet_NaN()), C::kNonFinitePosition, 30},
      {"too fast", at(40, 0.5), C::kEncoderJump, 40},  // 0.5 m in 1 ms: 500 m/s
      {"device fault",
       [](std::uint64_t t, PositionSample& s) {
         s.position = 0.0;
         return t < 50 ? IoStatus::kOk : IoStatus::kDeviceFault;
       },
       C::kDeviceReported, 50},
  };
}

TEST(IdentifyRun, FaultsWhereverARunFaultsWithTheSameCauseAtTheSameTick) {
  ExcitationLimits l = limits(false, 1.0);
  l.samples.stale_fault_ticks = 5;
  for (const Misbehaviour& m : misbehaviours()) {
    SCOPED_TRACE(m.name);
    hapticd::testing::ScriptedDevice for_run;
    for_run.script = m.script;
    loop::LoopOptions o;
    o.sample.realtime = false;
    o.max_ticks = 100;
    o.sample.stale_fault_ticks = l.samples.stale_fault_ticks;
    config::Config c = config::load_embedded_default();
    control::Controller law(control::make_control_law(c));
    loop::ServoLoop servo(for_run, law, nullptr, o);
    const std::atomic<bool> stop{false};
    const loop::LoopResult r = servo.run(stop);
    EXPECT_EQ(r.fault.cause, m.cause) << loop::describe(r.fault);
    EXPECT_EQ(r.fault.tick, m.tick);

    hapticd::testing::ScriptedDevice for_identify;
    for_identify.script = m.script;
    const std::vector<double> u(100, 0.5);
    ExcitationRecord rec(u.size());
    run_excitation(for_identify, u, l, stop, rec);
    EXPECT_EQ(rec.end, ExcitationEnd::kFault);
    EXPECT_EQ(rec.fault.cause, m.cause) << loop::describe(rec.fault);
    EXPECT_EQ(rec.fault.tick, m.tick);
    ASSERT_FALSE(for_identify.writes.empty());
    EXPECT_EQ(for_identify.writes.back(), 0.0);
    EXPECT_FALSE(for_identify.output_enabled());
  }
}

// And the schedule: a device slower than the period overruns identify's ticks as it overruns
// a run's, and loop.overrun_fault_streak of them in a row fault it.
TEST(IdentifyRun, AStreakOfOverrunsFaultsItAsItFaultsARun) {
  hapticd::testing::ScriptedDevice slow;
  slow.read_sleep_ns = 3'000'000;  // 3 ms reads at 1 kHz
  ExcitationLimits l = limits(true, 1.0);
  l.overrun_fault_streak = 4;
  const std::vector<double> u(100, 0.1);
  ExcitationRecord rec(u.size());
  const std::atomic<bool> stop{false};
  run_excitation(slow, u, l, stop, rec);
  EXPECT_EQ(rec.end, ExcitationEnd::kFault);
  EXPECT_EQ(rec.fault.cause, loop::FaultCause::kOverrunStreak);
  EXPECT_EQ(rec.fault.tick, 3u);
  EXPECT_EQ(slow.writes.back(), 0.0);
}

}  // namespace
}  // namespace hapticd::service
