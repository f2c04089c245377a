// The servo loop through each profile and its simulated drive, in freerun: the wall renders
// as the sim driver renders it with the same plant, wall and total delay; each injected fault
// faults the loop within the tick that sees it, with zero force and the cause named.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "can_rig.h"
#include "control/controller.h"
#include "loop/servo_loop.h"
#include "sim/peers/paced_device.h"

namespace hapticd::drivers::can::testing {
namespace {

loop::LoopOptions options(const config::Config& cfg, std::uint64_t ticks) {
  loop::LoopOptions o;
  o.sample.realtime = false;
  o.sample.period_ns = std::llround(cfg.loop.sample_period_s() * 1e9);
  o.max_ticks = ticks;
  o.sample.stale_fault_ticks = cfg.safety.stale_fault_ticks;
  o.sample.max_speed = cfg.safety.max_speed;
  return o;
}

// The sim driver on the same file: the can section switched off, the driver's delay added to
// the wall's own.
loop::LoopResult run_sim(const char* example, int delay) {
  const config::Config cfg = load_example(example, {"device.driver=sim", "device.can=null",
                                                    "wall.delay_samples=" + std::to_string(delay)});
  wiring::Loopback pair = wiring::find_driver("sim").make_loopback(cfg);
  pair.device->configure();
  pair.device->enable();
  control::Controller controller(control::make_control_law(cfg));
  loop::ServoLoop servo(*pair.device, controller, nullptr, options(cfg, 2500));
  const std::atomic<bool> stop{false};
  return servo.run(stop);
}

loop::LoopResult run_can(const char* example) {
  const config::Config cfg = load_example(example);
  CanRig rig(cfg);
  sim::PacedDevice device(std::move(rig.pair.device), rig.runner);
  rig.pair.device = nullptr;
  device.configure();
  device.enable();
  control::Controller controller(control::make_control_law(cfg));
  loop::ServoLoop servo(device, controller, nullptr, options(cfg, 2500));
  const std::atomic<bool> stop{false};
  const loop::LoopResult r = servo.run(stop);
  device.close();
  return r;
}

class CanRun : public ::testing::TestWithParam<const char*> {};

TEST_P(CanRun, RendersTheWallAsTheSimDriverDoesWithTheSameTotalDelay) {
  const loop::LoopResult can = run_can(GetParam());
  const loop::LoopResult sim = run_sim(GetParam(), 1);
  ASSERT_EQ(can.fault.cause, loop::FaultCause::kNone) << loop::describe(can.fault);
  ASSERT_EQ(sim.fault.cause, loop::FaultCause::kNone) << loop::describe(sim.fault);
  EXPECT_GT(can.count(loop::kCounterContactTicks), 500u) << "the hand presses into the wall";
  EXPECT_LE(can.count(loop::kCounterStaleTicks), 1u)
      << "only the first tick, before the first SYNC";
  EXPECT_NEAR(can.max_penetration, sim.max_penetration, 0.1 * sim.max_penetration)
      << "can " << can.max_penetration * 1e3 << " mm, sim " << sim.max_penetration * 1e3 << " mm";
  RecordProperty("penetration_can_mm", std::to_string(can.max_penetration * 1e3));
  RecordProperty("penetration_sim_mm", std::to_string(sim.max_penetration * 1e3));
}

// Every fault the drive can produce, injected while the wall pushes: the loop faults with the
// right cause, zero force at once, and the description names the cause and the code.
TEST_P(CanRun, EachInjectedFaultEndsTheLoopWithZeroForceAndItsCauseNamed) {
  struct Fault {
    const char* name;
    bool can_fault;
    int fault;
    loop::FaultCause cause;
    const char* named;
  };
  const bool cia = std::string(GetParam()) == "can-cia402.yaml";
  const Fault faults[] = {
      {"device", false, static_cast<int>(sim::PeerFault::kDeviceFault),
       loop::FaultCause::kDeviceReported, cia ? "EMCY 0x2310" : "CURRENT_LIMIT_VIOLATION"},
      {"bus", false, static_cast<int>(sim::PeerFault::kTransportFault),
       loop::FaultCause::kTransportRead, "bus-off"},
      {"stale", false, static_cast<int>(sim::PeerFault::kStopAnswering),
       loop::FaultCause::kStaleData, ""},
      {"heartbeat", true, static_cast<int>(sim::CanPeerFault::kStopHeartbeat),
       loop::FaultCause::kDeviceReported, "no heartbeat"},
  };
  for (const Fault& f : faults) {
    SCOPED_TRACE(f.name);
    const config::Config cfg = load_example(
        GetParam(), {"device.sim.initial_position=-0.0005",
                     "device.sim.operator={kind: force, force: {shape: constant, value: 3}}"});
    CanRig rig(cfg);
    sim::PacedDevice device(std::move(rig.pair.device), rig.runner);
    device.configure();
    device.enable();
    control::Controller controller(control::make_control_law(cfg));
    loop::ServoLoop servo(device, controller, nullptr, options(cfg, 100'000));
    const std::atomic<bool> stop{false};
    loop::LoopResult r;
    std::thread t([&] { r = servo.run(stop); });
    while (servo.ticks_done() < 300) std::this_thread::yield();
    ASSERT_TRUE(f.can_fault ? rig.peer().inject_can(static_cast<sim::CanPeerFault>(f.fault))
                            : rig.peer().inject(static_cast<sim::PeerFault>(f.fault)));
    t.join();
    EXPECT_EQ(r.fault.cause, f.cause) << loop::describe(r.fault);
    EXPECT_GT(r.count(loop::kCounterContactTicks), 100u);
    rig.settle();
    EXPECT_EQ(rig.peer().applied_force(), 0.0);
    EXPECT_EQ(device.last_command(), 0.0);
    if (*f.named != '\0') {
      EXPECT_NE(device.describe_fault().find(f.named), std::string::npos)
          << device.describe_fault();
    }
    device.close();
    rig.settle();
    EXPECT_FALSE(rig.peer().output_on());
  }
}

INSTANTIATE_TEST_SUITE_P(Profiles, CanRun, ::testing::Values("can-cia402.yaml", "can-odrive.yaml"));

}  // namespace
}  // namespace hapticd::drivers::can::testing

namespace hapticd::drivers::can::testing {
namespace {

// Issue 23, 8: a real-time `--loopback` run on a loaded host. This machine's kernel does not
// preempt a task in the kernel (PREEMPT_NONE): a trace showed both cores held 30 ms, the loop
// and the simulated drive woken at SCHED_FIFO and waiting. The in-process drive counts time by
// its protocol (SYNC), and the device is paced by it, so a stall is no lost master and no old
// sample; a drive on a real bus (`hapticd peer`) keeps its wall-clock watchdogs.
TEST(CanRealTimeLoopback, AHostStallIsNeitherALostMasterNorAnOldSample) {
  const config::Config cfg = load_example("can-cia402.yaml", {"loop.clock=realtime"}, false);
  wiring::Loopback pair = wiring::find_driver("can").make_loopback(cfg);
  sim::PeerRunner runner(*pair.peer);
  sim::PacedDevice device(std::move(pair.device), runner);
  device.configure();
  device.enable();
  PositionSample s;
  const auto tick = [&] {
    const IoStatus r = device.read(s);
    if (r == IoStatus::kDeviceFault || r == IoStatus::kTransportFault) return r;
    return device.write(0.5);
  };
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(tick(), IoStatus::kOk) << device.describe_fault();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(80));  // the host holds everything
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(tick(), IoStatus::kOk) << device.describe_fault();
    EXPECT_EQ(device.read(s), IoStatus::kOk) << "paced: the answer is there at the next read";
    EXPECT_EQ(s.flags & kSampleHasTime, 0) << "no wall-clock time from an in-process device";
  }
  device.close();
  runner.stop();
}

// A drive on a bus (`hapticd peer`) watches SYNC by the wall clock. A stall of hapticd longer
// than 20 cycles but shorter than the heartbeat consumer time it gave the drive
// (drive_watchdog_ms) is no lost master: the systemd machine's emulator once held hapticd over
// 200 ms at 100 Hz and the simulated drive sent EMCY 0x8100 though the configuration tolerated
// 1 s. A silence past drive_watchdog_ms still switches the drive off.
TEST(CanRealTimePeer, AStallShorterThanTheDrivesWatchdogIsNoLostMaster) {
  const config::Config cfg = load_example(
      "can-cia402.yaml", {"loop.rate_hz=100", "device.can.cia402.drive_watchdog_ms=1000",
                          "device.can.heartbeat_timeout_ms=5000"});
  CanRig rig(cfg, cfg, true);
  rig.device().configure();
  rig.device().enable();
  PositionSample s;
  const auto ticks = [&](int n) {
    for (int i = 0; i < n; ++i) {
      const IoStatus r = rig.tick(0.5, s);
      ASSERT_TRUE(r == IoStatus::kOk || r == IoStatus::kNoNewData) << rig.device().describe_fault();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  };
  ticks(20);
  std::this_thread::sleep_for(std::chrono::milliseconds(400));  // 40 cycles, 0.4 of the watchdog
  ticks(20);
  EXPECT_TRUE(rig.peer().output_on()) << "the drive switched off on a stall it was told to bear";
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_FALSE(rig.peer().output_on()) << "hapticd silent past drive_watchdog_ms";
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
