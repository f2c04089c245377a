// What real drives do that the first simulated ones did not (issue 34), against the simulated
// drives over a socketpair: a CiA 402 position actual value (0x6064) that rolls over at 2^31
// while the wall holds the axis, a drive whose DC link is still charging when hapticd enables
// it (or never charges), an ODrive 0.6 that disarms by itself and says why only in Get_Error.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "can_rig.h"
#include "control/controller.h"
#include "loop/servo_loop.h"
#include "sim/peers/can/cia402_peer.h"
#include "sim/peers/can/odrive_peer.h"
#include "sim/peers/paced_device.h"

namespace hapticd::drivers::can::testing {
namespace {

// The example's 0x6064 increment.
constexpr double kMetresPerCount = 1e-5;
// 2^31 - 100: the wall at this count puts the rollover 1 mm inside it, where the example's hand
// holds the axis (2.3 mm in: 300 N/m x 7.7 mm = 1000 N/m x 2.3 mm).
constexpr std::int64_t kWallCount = 2147483548;

std::string metres(double m) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", m);
  return text;
}

loop::LoopResult run_loop(const config::Config& cfg, CanRig& rig) {
  sim::PacedDevice device(std::move(rig.pair.device), rig.runner);
  rig.pair.device = nullptr;
  device.configure();
  device.enable();
  control::Controller controller(control::make_control_law(cfg));
  loop::LoopOptions o;
  o.sample.realtime = false;
  o.sample.period_ns = std::llround(cfg.loop.sample_period_s() * 1e9);
  o.max_ticks = 2500;  // the press (0.2 s), its ramp in, the hold, the ramp out
  o.sample.stale_fault_ticks = cfg.safety.stale_fault_ticks;
  o.sample.max_speed = cfg.safety.max_speed;
  loop::ServoLoop servo(device, controller, nullptr, o);
  const std::atomic<bool> stop{false};
  const loop::LoopResult r = servo.run(stop);
  device.close();
  return r;
}

// Issue 34, 1: a drive that keeps an offset puts the wall's rest beyond 2^31 - 1; the count
// continues at -2^31 as the hand presses in and comes back as it lets go. The run renders the
// same wall as with no offset (before the fix: a jump of 2^32 counts, a speed fault).
TEST(CanRealDrive, A0x6064ThatRollsOverInContactRendersTheSameWall) {
  const config::Config plain = load_example("can-cia402.yaml");
  CanRig plain_rig(plain);
  const loop::LoopResult reference = run_loop(plain, plain_rig);
  ASSERT_EQ(reference.fault.cause, loop::FaultCause::kNone) << loop::describe(reference.fault);

  const config::Config offset =
      load_example("can-cia402.yaml", {"wall.position=" + metres(kWallCount * kMetresPerCount)});
  CanRig rig(offset);
  dynamic_cast<sim::Cia402Peer&>(rig.peer()).offset_position(kWallCount);
  const loop::LoopResult r = run_loop(offset, rig);
  ASSERT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
  EXPECT_GT(r.max_penetration, 150 * kMetresPerCount) << "pressed across the rollover (100)";
  EXPECT_NEAR(r.max_penetration, reference.max_penetration, 1.5 * kMetresPerCount);
  EXPECT_EQ(r.count(loop::kCounterContactTicks), reference.count(loop::kCounterContactTicks))
      << "and back out across it";
  RecordProperty("penetration_mm", std::to_string(r.max_penetration * 1e3));
}

// The first sample after configure is the count as the drive sends it (sign-extended); a
// re-enable continues from the last sample, not from the raw count.
TEST(CanRealDrive, TheUnwrappedPositionStartsAtTheRawCountAndSurvivesAReEnable) {
  const config::Config cfg = load_example(
      "can-cia402.yaml", {"device.sim.operator={kind: force, force: {shape: constant, value: 0}}",
                          "device.sim.initial_position=0"});
  CanRig rig(cfg);
  auto& drive = dynamic_cast<sim::Cia402Peer&>(rig.peer());
  drive.offset_position(kWallCount + 90);  // 10 counts below +2^31 - 1
  rig.device().configure();
  rig.device().enable();
  PositionSample s;
  rig.tick(0.0, s);
  ASSERT_EQ(rig.tick(0.0, s), IoStatus::kOk) << rig.device().describe_fault();
  EXPECT_NEAR(s.position, (kWallCount + 90) * kMetresPerCount, 1e-9);
  rig.device().disable();
  rig.settle();
  drive.offset_position(kWallCount + 120);  // moved 30 counts while off: across the rollover
  rig.device().enable();
  rig.tick(0.0, s);
  ASSERT_EQ(rig.tick(0.0, s), IoStatus::kOk) << rig.device().describe_fault();
  EXPECT_NEAR(s.position, (kWallCount + 120) * kMetresPerCount, 1e-9)
      << "not -2^31 + 20 counts: the same session, unwrapped";
  rig.device().close();
  rig.settle();
  rig.device().configure();  // a new session: the first sample is the raw count again
  rig.device().enable();
  rig.tick(0.0, s);
  ASSERT_EQ(rig.tick(0.0, s), IoStatus::kOk) << rig.device().describe_fault();
  EXPECT_NEAR(s.position, (kWallCount + 120 - 4294967296LL) * kMetresPerCount, 1e-9);
}

std::string enable_error(CanRig& rig) {
  try {
    rig.device().enable();
  } catch (const DeviceError& e) {
    return e.what();
  }
  return "";
}

// Issue 34, 2: mains switched on with hapticd: the drive refuses the shutdown command until
// its DC link has charged (1.2 s here, beyond state_timeout_ms 500), bit 4 at 0 meanwhile.
TEST(CanRealDrive, ADriveWhoseDcLinkIsChargingIsEnabledOnceCharged) {
  CanRig rig(load_example("can-cia402.yaml"));
  auto& drive = dynamic_cast<sim::Cia402Peer&>(rig.peer());
  rig.device().configure();
  drive.charge_dc_link_after(1200);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(enable_error(rig), "");
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, std::chrono::milliseconds(1100)) << "the drive cannot have moved sooner";
  EXPECT_EQ(drive.power_state(), cia402::PowerState::kOperationEnabled);
  EXPECT_EQ(rig.device().state(), DeviceState::kActive);
}

TEST(CanRealDrive, ADriveWhoseDcLinkNeverChargesIsRefusedNamingIt) {
  CanRig rig(load_example("can-cia402.yaml", {"device.can.cia402.dc_link_timeout_ms=800"}));
  auto& drive = dynamic_cast<sim::Cia402Peer&>(rig.peer());
  drive.charge_dc_link_after(-1);  // no mains
  rig.device().configure();
  const std::string e = enable_error(rig);
  EXPECT_NE(e.find("the drive reports no DC-link voltage (statusword 0x0240 switch on disabled, "
                   "remote: bit 4, voltage enabled, is 0) after 800 ms"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("device.can.cia402.dc_link_timeout_ms (800)"), std::string::npos) << e;
  EXPECT_EQ(rig.device().state(), DeviceState::kConfigured);
  EXPECT_FALSE(rig.peer().output_on());
}

// Issue 34, 3: an ODrive 0.6 disarmed by a short DC-bus dip is IDLE without an active error by
// its next heartbeat. The RT path latches the fault (zero torque) and asks Get_Error with it,
// without waiting; disable takes the answer, and the fault names the disarm reason.
TEST(CanRealDrive, AnOdrive06ThatDisarmsByItselfIsAskedWhy) {
  CanRig rig(load_example("can-odrive.yaml"));  // firmware auto: the simulated axis is 0.6
  auto& axis = dynamic_cast<sim::OdrivePeer&>(rig.peer());
  rig.device().configure();
  rig.device().enable();
  ASSERT_EQ(rig.run_until_fault(0.5, 5), IoStatus::kOk) << rig.device().describe_fault();
  ASSERT_TRUE(rig.peer().inject_can(sim::CanPeerFault::kDisarm));
  ASSERT_EQ(rig.run_until_fault(0.5, 10), IoStatus::kDeviceFault);
  EXPECT_EQ(rig.peer().applied_force(), 0.0);
  EXPECT_EQ(rig.device().last_command(), 0.0);
  EXPECT_EQ(axis.error_requests(), 1) << "asked from the RT path, with the latch's zero torque";
  rig.device().disable();
  rig.settle();
  EXPECT_EQ(axis.error_requests(), 1) << "disable took the answer already on its way";
  const std::string why = rig.device().describe_fault();
  EXPECT_NE(why.find("left CLOSED_LOOP_CONTROL by itself: its heartbeat says IDLE; disarm reason "
                     "(Get_Error) 0x00000200 DC_BUS_UNDER_VOLTAGE, active errors now 0x00000000 "
                     "(no error)"),
            std::string::npos)
      << why;
  rig.device().clear_fault();  // Clear_Errors clears the disarm reason too
  rig.device().enable();
  EXPECT_EQ(rig.run_until_fault(0.5, 5), IoStatus::kOk) << rig.device().describe_fault();
}

// 0.5 has no Get_Error (0x003 is Get_Motor_Error there): an axis leaving closed loop is named
// as before, and nothing is asked.
TEST(CanRealDrive, AnOdrive05IsNotAskedForGetError) {
  const config::Config cfg = load_example("can-odrive.yaml", {"device.can.odrive.firmware=0.5"});
  CanRig rig(cfg);
  EXPECT_FALSE(rig.peer().inject_can(sim::CanPeerFault::kDisarm)) << "no disarm reason on 0.5";
  rig.device().configure();
  rig.device().enable();
  ASSERT_EQ(rig.run_until_fault(0.5, 5), IoStatus::kOk) << rig.device().describe_fault();
  ASSERT_TRUE(rig.peer().inject(sim::PeerFault::kDeviceFault));
  ASSERT_EQ(rig.run_until_fault(0.5, 10), IoStatus::kDeviceFault);
  rig.device().disable();
  rig.settle();
  EXPECT_EQ(dynamic_cast<sim::OdrivePeer&>(rig.peer()).error_requests(), 0);
  EXPECT_EQ(rig.device().describe_fault().find("Get_Error"), std::string::npos)
      << rig.device().describe_fault();
}

TEST(CanRealDrive, ADcLinkTimeOutOutsideItsRangeIsRefusedByKey) {
  try {
    load_example("can-cia402.yaml", {"device.can.cia402.dc_link_timeout_ms=-5"});
    FAIL() << "loaded a negative dc_link_timeout_ms";
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const std::string& m : e.messages()) all += m + "\n";
    EXPECT_NE(all.find("device.can.cia402.dc_link_timeout_ms: must be in 0..600000, got '-5'"),
              std::string::npos)
        << all;
  }
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
