// `hapticd run` on vcan0 in the kernel test machine against reference drives doing what real
// ones do (issue 34): a CiA 402 drive whose 0x6064 rolls over at 2^31 while the wall holds the
// axis, in both directions; a drive whose DC link charges only after hapticd asked, and one
// that never gets mains; an ODrive Pro / S1 (0.6) that a DC-bus dip disarms.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "reference/can/cia402_drive.h"
#include "reference/can/odrive_06.h"
#include "reference_kernel_rig.h"
#include "sysfs.h"
#include "vcan_interface.h"

namespace hapticd::drivers::can::testing {
namespace {

reference::Cia402Behaviour cia402_drive() {
  reference::Cia402Behaviour b;
  b.rated_torque_mnm = 5;         // as can_reference_kernel_test.cpp: 0.5 mN at this transmission
  b.max_torque_permille = 30000;  // 0.15 N m, above max_torque
  return b;
}

// Crossings of the rollover in the 0x6064 values the drive sent (TPDO1, bytes 2-5): up (from
// near +2^31 to near -2^31) and down.
// The line of the run's output that holds `what`, for the test's record.
std::string line_with(const std::string& out, const std::string& what) {
  const auto at = out.find(what);
  if (at == std::string::npos) return {};
  const auto begin = out.rfind('\n', at);
  const auto end = out.find('\n', at);
  return out.substr(begin == std::string::npos ? 0 : begin + 1,
                    end == std::string::npos ? std::string::npos : end - begin - 1);
}

struct Crossings {
  int up = 0, down = 0;
};
Crossings rollovers(const std::vector<reference::LoggedFrame>& log) {
  Crossings c;
  bool have = false;
  std::int32_t last = 0;
  constexpr std::int64_t kNear = 1'000'000'000;
  for (const reference::LoggedFrame& l : log) {
    if (!l.sent || l.frame.id != 0x181 || l.frame.len != 6) continue;
    const auto count = static_cast<std::int32_t>(l.frame.u32(2));
    if (have && last > kNear && count < -kNear) ++c.up;
    if (have && last < -kNear && count > kNear) ++c.down;
    last = count;
    have = true;
  }
  return c;
}

void expect_rest(const reference::Cia402Drive& drive, double force, const ChildProcess& run,
                 const char* what) {
  const double x = rest_position(drive, 1000);
  const double expected = force / kCia402Rig.stiffness;
  EXPECT_NEAR(x, expected, 0.02 * expected) << what << "\n" << run.output();
  ::testing::Test::RecordProperty(std::string("rest_mm_") + what, std::to_string(x * 1e3));
}

// Issue 34, 1: the wall sits 1500 counts below the rollover. The hand's 0.1 N holds the axis
// 2000 counts in (past +2^31 - 1), its 0.05 N 1000 counts in (back below it), and 0.1 N again:
// three crossings in contact, each rest within 2 % of F/K, no fault.
TEST(CanRealDriveOnVcan, Cia402PositionRollingOverInContactRendersTheWall) {
  kernel_test::VcanInterface bus("vcan0");
  reference::Cia402Behaviour b = cia402_drive();
  b.position_offset = 2147483648LL - 1500;  // the wall (the plant's 0) at this count
  reference::Cia402Drive drive(b, hand(kCia402Rig.hand_force, 3.0), reference::monotonic_ns());
  reference::ReferenceRunner runner(drive, reference::CanPort::open("vcan0"));
  char wall[64];
  std::snprintf(wall, sizeof wall, "wall.position=%.17g",
                static_cast<double>(b.position_offset) * b.metres_per_increment);
  ChildProcess run(run_args("cia402", 120, {wall}), "/tmp/hapticd-ref-rollover.out");
  kernel_test::wait_until([&] { return drive.torque_on(); }, milliseconds(60'000),
                          "operation enabled");
  ASSERT_TRUE(wait_for_armed_wall(run, milliseconds(60'000))) << run.output();
  drive.press_now();
  std::this_thread::sleep_for(milliseconds(10'000));  // back from the check's pulse, then in
  expect_rest(drive, kCia402Rig.hand_force, run, "pressed");
  drive.set_hand_force(kCia402Rig.hand_force / 2);
  std::this_thread::sleep_for(milliseconds(5000));
  expect_rest(drive, kCia402Rig.hand_force / 2, run, "eased");
  drive.set_hand_force(kCia402Rig.hand_force);
  std::this_thread::sleep_for(milliseconds(5000));
  expect_rest(drive, kCia402Rig.hand_force, run, "pressed_again");
  run.signal(SIGTERM);
  EXPECT_EQ(run.wait(seconds(60)), 0) << run.output();
  runner.stop();
  const Crossings c = rollovers(runner.log());
  EXPECT_GE(c.up, 2) << "0x6064 went past +2^31 - 1 to -2^31 twice";
  EXPECT_GE(c.down, 1) << "and back once";
  RecordProperty("rollovers", std::to_string(c.up) + " up, " + std::to_string(c.down) + " down");
  EXPECT_NE(run.output().find("faults         none"), std::string::npos) << run.output();
}

// Issue 34, 2: mains come on once hapticd has asked for the shutdown command; the DC link
// then takes 3 s (beyond state_timeout_ms 2000): hapticd waits, and renders the wall.
TEST(CanRealDriveOnVcan, Cia402DriveWhoseDcLinkChargesLateRunsOnceCharged) {
  kernel_test::VcanInterface bus("vcan0");
  reference::Cia402Behaviour b = cia402_drive();
  b.mains_on_at_start = false;
  b.dc_link_charge_ms = 3000;
  reference::Cia402Drive drive(b, hand(kCia402Rig.hand_force, 3.0), reference::monotonic_ns());
  reference::ReferenceRunner runner(drive, reference::CanPort::open("vcan0"));
  ChildProcess run(run_args("cia402", 120, {"device.can.cia402.dc_link_timeout_ms=30000"}),
                   "/tmp/hapticd-ref-dc-link.out");
  kernel_test::wait_until([&] { return drive.dc_link_refusals() > 0; }, milliseconds(60'000),
                          "the shutdown command while the DC link is not charged");
  drive.switch_mains_on();
  kernel_test::wait_until([&] { return drive.torque_on(); }, milliseconds(60'000),
                          "operation enabled");
  ASSERT_TRUE(wait_for_armed_wall(run, milliseconds(60'000))) << run.output();
  drive.press_now();
  std::this_thread::sleep_for(milliseconds(10'000));
  expect_rest(drive, kCia402Rig.hand_force, run, "charged");
  run.signal(SIGTERM);
  EXPECT_EQ(run.wait(seconds(60)), 0) << run.output();
  runner.stop();
}

TEST(CanRealDriveOnVcan, Cia402DriveWithoutMainsIsRefusedNamingTheDcLink) {
  kernel_test::VcanInterface bus("vcan0");
  reference::Cia402Behaviour b = cia402_drive();
  b.mains_on_at_start = false;
  reference::Cia402Drive drive(b, hand(kCia402Rig.hand_force, 3.0), reference::monotonic_ns());
  reference::ReferenceRunner runner(drive, reference::CanPort::open("vcan0"));
  ChildProcess run(run_args("cia402", 10, {"device.can.cia402.dc_link_timeout_ms=4000"}),
                   "/tmp/hapticd-ref-no-mains.out");
  EXPECT_EQ(run.wait(seconds(120)), 4) << run.output();
  EXPECT_NE(run.output().find("the drive reports no DC-link voltage"), std::string::npos)
      << run.output();
  EXPECT_NE(run.output().find("device.can.cia402.dc_link_timeout_ms"), std::string::npos)
      << run.output();
  EXPECT_EQ(run.output().find("output enabled"), std::string::npos) << run.output();
  RecordProperty("refusal", line_with(run.output(), "DC-link"));
  runner.stop();
  EXPECT_FALSE(drive.torque_on());
}

// The last Set_Input_Torque (0x00E) the axis received, in N m.
float last_torque_command(const std::vector<reference::LoggedFrame>& log) {
  float torque = std::numeric_limits<float>::quiet_NaN();
  for (const reference::LoggedFrame& l : log) {
    if (!l.sent && !l.frame.rtr && l.frame.id == ((1u << 5) | 0x00E)) torque = l.frame.f32(0);
  }
  return torque;
}

// Issue 34, 3: an ODrive Pro / S1 disarmed by a DC-bus dip shorter than its heartbeat period:
// its next heartbeat says IDLE with no active error. The run ends with zero force, naming the
// disarm reason Get_Error gives.
TEST(CanRealDriveOnVcan, Odrive06DisarmedByADcBusDipEndsNamingTheReason) {
  kernel_test::VcanInterface bus("vcan0");
  reference::Odrive06 axis({}, hand(kOdriveRig.hand_force, 10.0), reference::monotonic_ns());
  reference::ReferenceRunner runner(axis, reference::CanPort::open("vcan0"));
  ChildProcess run(run_args("odrive", 120, {"device.can.odrive.vel_limit=0"}),
                   "/tmp/hapticd-ref-odrive06.out");
  kernel_test::wait_until([&] { return axis.armed(); }, milliseconds(60'000),
                          "the axis in closed loop");
  ASSERT_TRUE(wait_for_armed_wall(run, milliseconds(60'000))) << run.output();
  axis.press_now();
  std::this_thread::sleep_for(milliseconds(3000));
  const double x = rest_position(axis, 1000);
  const double expected = kOdriveRig.hand_force / kOdriveRig.stiffness;
  EXPECT_NEAR(x, expected, 0.02 * expected) << run.output();
  RecordProperty("rest_mm", std::to_string(x * 1e3));
  ASSERT_TRUE(axis.armed()) << run.output();
  axis.dip_dc_bus(20);
  EXPECT_EQ(run.wait(seconds(60)), 1) << run.output();
  const std::string out = run.output();
  EXPECT_NE(out.find("left CLOSED_LOOP_CONTROL by itself: its heartbeat says IDLE; disarm reason "
                     "(Get_Error) 0x00000200 DC_BUS_UNDER_VOLTAGE"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("zero force commanded, output disabled"), std::string::npos) << out;
  RecordProperty("fault", line_with(out, "fault: "));
  runner.stop();
  EXPECT_FALSE(axis.armed());
  EXPECT_EQ(axis.active_errors(), 0u) << "the dip was over by the heartbeat that said IDLE";
  EXPECT_EQ(axis.motor_force_n(), 0.0);
  EXPECT_EQ(last_torque_command(runner.log()), 0.0f) << "the last torque hapticd sent";
  EXPECT_GE(axis.error_requests(), 1);
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
