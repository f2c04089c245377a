// `hapticd run` as a person runs it against the reference drives (tests/reference/can) on
// vcan0 in the kernel test machine: an ODrive 0.5 set up as docs/drivers/can.md asks (its
// watchdog on) straight after power-on, and CiA 402 drives with the behaviours real ones have.
// Each must start and render the wall to within 1 % of F/K at rest; a drive that limits its
// torque below max_torque is refused, named, before output is enabled; a killed hapticd leaves
// an ODrive that idles itself.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "child_process.h"
#include "reference/can/cia402_drive.h"
#include "reference/can/odrive_056.h"
#include "reference_kernel_rig.h"
#include "sysfs.h"
#include "vcan_interface.h"

namespace hapticd::drivers::can::testing {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

TEST(CanReferenceOnVcan, Odrive05WithItsWatchdogOnRendersTheWallAndIdlesWhenHapticdIsKilled) {
  kernel_test::VcanInterface bus("vcan0");
  reference::Odrive056Config c;
  c.watchdog_timeout_s = 1.0;  // the emulator's slow start of the RT thread
  // Damping 10 N s/m: the hand's 1 N moves it at most 0.1 m/s, below the firmware's default
  // vel_limit (2 turn/s, 0.196 m/s here), which stays on.
  reference::Odrive056 axis(c, hand(kOdriveRig.hand_force, 10.0), reference::monotonic_ns());
  reference::ReferenceRunner runner(axis, reference::CanPort::open("vcan0"));
  std::this_thread::sleep_for(milliseconds(1200));  // power-on, nobody talking: expired
  ASSERT_EQ(axis.axis_error(), reference::Odrive056::kWatchdogExpired);
  ChildProcess run(
      run_args("odrive", 60,
               {"device.can.odrive.watchdog_timeout_s=1", "device.can.odrive.vel_limit=2"}),
      "/tmp/hapticd-ref-odrive.out");
  kernel_test::wait_until([&] { return axis.armed(); }, milliseconds(60'000),
                          "the axis in closed loop");
  std::this_thread::sleep_for(milliseconds(500));
  axis.press_now();
  std::this_thread::sleep_for(milliseconds(3000));
  const double x = rest_position(axis, 1000);
  const double expected = kOdriveRig.hand_force / kOdriveRig.stiffness;
  EXPECT_NEAR(x, expected, 0.01 * expected) << run.output();
  RecordProperty("rest_mm", std::to_string(x * 1e3));
  ASSERT_TRUE(axis.armed()) << run.output();
  const auto killed = std::chrono::steady_clock::now();
  run.signal(SIGKILL);
  EXPECT_EQ(run.wait(seconds(10)), 128 + SIGKILL);
  // The published force follows the state at the plant's next step (reference_plant.h): wait
  // for both, the idle state and the force it holds.
  kernel_test::wait_until([&] { return !axis.armed() && axis.motor_force_n() == 0.0; },
                          milliseconds(3000), "the axis idling itself with zero force");
  const auto ms =
      std::chrono::duration_cast<milliseconds>(std::chrono::steady_clock::now() - killed).count();
  RecordProperty("idle_after_ms", std::to_string(ms));
  EXPECT_EQ(axis.axis_error(), reference::Odrive056::kWatchdogExpired);
  EXPECT_EQ(axis.motor_force_n(), 0.0);
  runner.stop();
}

// The drive's last `n` frames, each with its time (ms before the last), received or sent.
std::string last_frames(const std::vector<reference::LoggedFrame>& log, std::size_t n) {
  std::string out = "the drive's last frames (ms before the last; rx from the bus, tx its own):\n";
  const std::size_t from = log.size() > n ? log.size() - n : 0;
  char line[96];
  for (std::size_t i = from; i < log.size(); ++i) {
    const reference::LoggedFrame& l = log[i];
    int at =
        std::snprintf(line, sizeof line, "  %8.3f %s %03x", (log.back().time_ns - l.time_ns) * 1e-6,
                      l.sent ? "tx" : "rx", static_cast<unsigned>(l.frame.id));
    for (int b = 0; b < l.frame.len && at < 80; ++b)
      at += std::snprintf(line + at, sizeof line - static_cast<std::size_t>(at), " %02x",
                          l.frame.data[b]);
    out += line;
    out += "\n";
  }
  return out;
}

struct Cia402Case {
  const char* name;
  reference::Cia402Behaviour behaviour;
  std::vector<std::string> sets;
};

reference::Cia402Behaviour with(void (*f)(reference::Cia402Behaviour&)) {
  reference::Cia402Behaviour b;
  b.rated_torque_mnm = 5;         // 1 per mille: 0.5 mN at this transmission, 0.25 % of the hand
  b.max_torque_permille = 30000;  // 0.15 N m, above max_torque
  f(b);
  return b;
}

TEST(CanReferenceOnVcan, Cia402DrivesAsTheyAreStartAndRenderTheWall) {
  const Cia402Case cases[] = {
      {"bit 30 kept, 0x6061 late, no 0x1006, 0x60C2",
       with([](reference::Cia402Behaviour& b) {
         b.tpdo_cob_id_bit30_required = true;
         b.mode_display_lag_ms = 40;
         b.has_1006 = false;
         b.has_60c2 = true;
       }),
       {}},
      {"watching SYNC (0x1006) and hapticd's heartbeat",
       with([](reference::Cia402Behaviour&) {}),
       {}},
      {"no 0x6007, comm_loss_reaction none",
       with([](reference::Cia402Behaviour& b) { b.has_6007 = false; }),
       {"device.can.cia402.comm_loss_reaction=none"}},
  };
  for (const Cia402Case& k : cases) {
    SCOPED_TRACE(k.name);
    kernel_test::VcanInterface bus("vcan0");
    reference::Cia402Drive drive(k.behaviour, hand(kCia402Rig.hand_force, 3.0),
                                 reference::monotonic_ns());
    reference::ReferenceRunner runner(drive, reference::CanPort::open("vcan0"));
    ChildProcess run(run_args("cia402", 60, k.sets), "/tmp/hapticd-ref-cia402.out");
    kernel_test::wait_until([&] { return drive.torque_on(); }, milliseconds(60'000),
                            "operation enabled");
    // The hand pushes once the direction check has armed the wall: its pulse moves the axis
    // some 0.1 m out (3.2 s at 5 Hz), then the hand brings it back (3 s) and in (the slow
    // pole: 0.6 s).
    ASSERT_TRUE(wait_for_armed_wall(run, milliseconds(60'000))) << run.output();
    drive.press_now();
    std::this_thread::sleep_for(milliseconds(10'000));
    const double x = rest_position(drive, 1000);
    const double expected = kCia402Rig.hand_force / kCia402Rig.stiffness;
    EXPECT_NEAR(x, expected, 0.01 * expected) << run.output();
    RecordProperty(std::string("rest_mm_") + std::to_string(&k - cases), std::to_string(x * 1e3));
    run.signal(SIGTERM);  // a normal stop
    EXPECT_EQ(run.wait(seconds(60)), 0) << run.output();
    std::this_thread::sleep_for(milliseconds(300));
    runner.stop();
    EXPECT_FALSE(drive.torque_on()) << last_frames(runner.log(), 60) << run.output();
    for (const reference::LoggedFrame& l : runner.log()) {
      if (l.sent && l.frame.id == 0x081) {
        EXPECT_EQ(l.frame.u16(0), 0u)
            << "EMCY " << std::hex << l.frame.u16(0) << ": " << run.output();
      }
    }
  }
}

TEST(CanReferenceOnVcan, ADriveLimitBelowMaxTorqueIsNamedBeforeOutputIsEnabled) {
  kernel_test::VcanInterface bus("vcan0");
  reference::Cia402Drive drive(with([](reference::Cia402Behaviour& b) {
                                 b.max_torque_permille = 500;  // 0.001 N m < 0.1
                               }),
                               hand(kCia402Rig.hand_force, 3.0), reference::monotonic_ns());
  reference::ReferenceRunner runner(drive, reference::CanPort::open("vcan0"));
  ChildProcess run(run_args("cia402", 3, {}), "/tmp/hapticd-ref-6072.out");
  EXPECT_EQ(run.wait(seconds(60)), 4) << run.output();
  EXPECT_NE(run.output().find("0x6072 = 500 per mille"), std::string::npos) << run.output();
  EXPECT_EQ(run.output().find("output enabled"), std::string::npos) << run.output();
  runner.stop();
  EXPECT_FALSE(drive.torque_on());
}

// Two CiA 402 reference drives on vcan0 as the joints of a cartesian XY gantry
// (config/can-gantry.yaml), each pushed by its own hand with the same force, against a wall
// whose normal is the diagonal: at rest at F sqrt(2) / K along it (the task force (F, F)), and
// an EMCY of the second drive ends the run with zero torque on both and the node named (the
// first's, and each node's heartbeat, over a socketpair: can_reference_nodes_test.cpp; one
// run here, as the emulated guest takes most of a minute to start one).
TEST(CanReferenceOnVcan, TwoCia402DrivesAsAGantryRenderADiagonalWallAndAFaultZeroesBoth) {
  for (const int faulty : {2}) {
    SCOPED_TRACE("the fault on node " + std::to_string(faulty));
    kernel_test::VcanInterface bus("vcan0");
    std::vector<std::unique_ptr<reference::Cia402Drive>> drives;
    std::vector<std::unique_ptr<reference::ReferenceRunner>> runners;
    for (std::uint8_t node : {1, 2}) {
      reference::Cia402Behaviour b = with([](reference::Cia402Behaviour&) {});
      b.node = node;
      drives.push_back(std::make_unique<reference::Cia402Drive>(b, hand(kCia402Rig.hand_force, 3.0),
                                                                reference::monotonic_ns()));
      runners.push_back(std::make_unique<reference::ReferenceRunner>(
          *drives.back(), reference::CanPort::open("vcan0")));
    }
    const std::vector<std::string> a = gantry_args(
        kCia402Rig,
        {"device.can.cia402.master_heartbeat_ms=200", "device.can.cia402.drive_watchdog_ms=1500"});
    ChildProcess run(a, "/tmp/hapticd-ref-gantry.out");
    kernel_test::wait_until([&] { return drives[0]->torque_on() && drives[1]->torque_on(); },
                            milliseconds(60'000), "both drives operation enabled");
    // The press's ramp (0.5 s), then its slow pole (each axis: 0.1 s^2 + 3 s + K/2, 1.2 s)
    // decays to 3e-4.
    for (auto& d : drives) d->press_now();
    std::this_thread::sleep_for(milliseconds(10'000));
    const double x = rest_position(*drives[0], 1000), y = rest_position(*drives[1], 1000);
    const double depth = (x + y) / std::sqrt(2.0);  // n . (x - 0)
    const double expected = kCia402Rig.hand_force * std::sqrt(2.0) / kCia402Rig.stiffness;
    EXPECT_NEAR(depth, expected, 0.02 * expected) << run.output();
    RecordProperty("rest_mm_" + std::to_string(faulty), std::to_string(depth * 1e3));
    ASSERT_GT(std::abs(drives[0]->motor_force_n()), 0.05) << "the wall pushes on both joints";
    ASSERT_GT(std::abs(drives[1]->motor_force_n()), 0.05);
    drives[faulty - 1]->inject_fault(0x2310);
    EXPECT_EQ(run.wait(seconds(60)), 1) << run.output();
    EXPECT_NE(run.output().find("node " + std::to_string(faulty)), std::string::npos)
        << run.output();
    std::this_thread::sleep_for(milliseconds(300));
    for (auto& r : runners) r->stop();
    for (auto& d : drives) {
      EXPECT_FALSE(d->torque_on()) << run.output();
      EXPECT_EQ(d->motor_force_n(), 0.0);
    }
  }
}

// Two ODrive 0.5 axes on one bus, one per joint of an XY gantry (docs/kinematics.md, several
// CAN drives): a diagonal wall holds the hand's (1 N, 1 N) at rest at its force along the normal
// over K, and a motor failure on one axis ends the run naming it, both axes idle with zero force.
TEST(CanReferenceOnVcan, TwoOdriveAxesAsAGantryRenderADiagonalWallAndAFaultIdlesBoth) {
  kernel_test::VcanInterface bus("vcan0");
  OdriveGantryAxes gantry(kOdriveRig.hand_force);
  auto& axes = gantry.axes;
  const std::vector<std::string> a = gantry_args(kOdriveRig, odrive_gantry_sets());
  ChildProcess run(a, "/tmp/hapticd-ref-odrive-gantry.out");
  kernel_test::wait_until([&] { return axes[0]->armed() && axes[1]->armed(); },
                          milliseconds(60'000), "both axes in closed loop");
  std::this_thread::sleep_for(milliseconds(500));
  for (auto& x : axes) x->press_now();
  std::this_thread::sleep_for(milliseconds(4000));
  const double x = rest_position(*axes[0], 1000), y = rest_position(*axes[1], 1000);
  const double depth = (x + y) / std::sqrt(2.0);  // n . (x - 0)
  const double expected = kOdriveRig.hand_force * std::sqrt(2.0) / kOdriveRig.stiffness;
  EXPECT_NEAR(depth, expected, 0.02 * expected) << run.output();
  RecordProperty("rest_mm", std::to_string(depth * 1e3));
  ASSERT_GT(std::abs(axes[0]->motor_force_n()), 0.3) << "the wall pushes on both joints";
  ASSERT_GT(std::abs(axes[1]->motor_force_n()), 0.3);
  axes[1]->raise_axis_error(reference::Odrive056::kMotorFailed);
  EXPECT_EQ(run.wait(seconds(60)), 1) << run.output();
  EXPECT_NE(run.output().find("node 2"), std::string::npos) << run.output();
  kernel_test::wait_until(
      [&] {
        return !axes[0]->armed() && !axes[1]->armed() && axes[0]->motor_force_n() == 0.0 &&
               axes[1]->motor_force_n() == 0.0;
      },
      milliseconds(3000), "both axes idle with zero force");
  for (auto& r : gantry.runners) r->stop();
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
