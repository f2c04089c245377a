// hapticd's evdev driver against the reference OpenFFBoard (openffboard.h) behind the kernel's
// own PID host: on the raw gadget the board is a USB device with a complete PID descriptor, so
// usbhid binds hid-pidff to it, and hapticd meets it as /dev/input/eventN with FF_CONSTANT
// (device.evdev.ff_driver pidff). With config/evdev.yaml's direction 270 (0xC000, which
// hid-pidff passes on as the PID Direction) the wall must hold the hand's push at F/K within
// 2 %, as it does through the HID driver; and what the board receives each tick is counted:
// hid-pidff sends a Set Constant Force report for an update only when the level changed.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "hapticd_process.h"
#include "hid_support.h"
#include "openffboard.h"

namespace hapticd::reference {
namespace {

constexpr double kStiffness = 5.0;  // N m/rad: at 100 Hz the gate allows up to 9 with b 0.05
constexpr double kPush = 0.5;       // N m: the hand's steady push into the wall

// The emulated machine's thresholds: overruns, stale ticks and late updates (an EVIOCSFF through
// hid-pidff takes it milliseconds, above the 5 ms that update_latency_ms 0 covers) are counted,
// not faulted, below its stalls. As in the HID tests of this board, the wheel coasts (J/b = 1 s)
// from whatever moved it last (hid-pidff's probe at bind, a late zero): the direction check
// waits up to 5 s for rest, not the default 1 s, which a Debian 12 check's run missed ("never
// at rest before tick 99").
std::vector<std::string> evdev_sets(const std::string& serial) {
  return {"loop.rate_hz=100",
          "loop.overrun_fault_streak=1000",
          "safety.direction_check.max_latency_ms=300",
          "safety.direction_check.duration_ms=100",
          "safety.direction_check.rest_timeout_ms=5000",
          "safety.stale_fault_ticks=50",
          "device.evdev.late_update_fault=1000",
          "device.mass=0.05",
          "device.damping=0.05",
          "wall.stiffness=" + std::to_string(kStiffness),
          "wall.damping=0",
          "device.evdev.select={vendor_id: 0x1209, product_id: 0xffb0, uniq: \"" + serial + "\"}",
          "device.evdev.axis={code: ABS_X, min: -7.853982, max: 7.853982}",
          "device.evdev.force_full_scale=10",
          "device.evdev.ff_driver=pidff"};
}

TEST(OpenFfboardEvdev, BehindHidPidffTheWallHoldsTheHandAtForceOverStiffness) {
  OpenFfboardOptions o;
  o.usb_report_rate = 4;  // as the HID tests: what the emulated controller carries
  o.serial = "openffboard-evdev";
  auto board = std::make_unique<OpenFfboard>(o);
  ASSERT_TRUE(wait_until([&] {
    return kernel_test::hidraw_listed(3, OpenFfboard::kVendor, OpenFfboard::kProduct, o.serial);
  }));
  std::this_thread::sleep_for(std::chrono::seconds(1));  // hid-pidff's own probe at bind
  double x_rest = 0.0, torque_rest = 0.0;
  std::uint64_t constants = 0, outputs = 0;
  const double window_s = 2.0;
  const HapticdRun r =
      run_hapticd(shipped("evdev.yaml"), evdev_sets(o.serial), {"--duration", "7"}, [&](pid_t) {
        // Uploaded at configure, played at enable: the hand pushes once the wall is on, after
        // the direction check (about 0.2 s at 100 Hz with the wheel at rest).
        ASSERT_TRUE(wait_until([&] { return board->playing(); })) << "output never enabled";
        ASSERT_TRUE(wait_armed()) << "the direction check never armed the wall";
        board->axis().hand(kPush, 1.0);
        std::this_thread::sleep_for(std::chrono::milliseconds(2500));
        // At rest: the level no longer changes.
        const std::uint64_t c0 = board->constant_reports(), o0 = board->output_reports();
        std::this_thread::sleep_for(std::chrono::duration<double>(window_s));
        constants = board->constant_reports() - c0;
        outputs = board->output_reports() - o0;
        x_rest = board->axis().position();
        torque_rest = board->axis().motor();
      });
  ASSERT_EQ(r.status, 0) << r.faults() << "\n" << r.log;
  EXPECT_EQ(r.faults(), "[]");

  EXPECT_NEAR(x_rest, kPush / kStiffness, 0.02 * kPush / kStiffness)
      << "resting penetration; " << r.summary.dump() << "\n"
      << r.log;
  EXPECT_NEAR(torque_rest, -kPush, 0.02 * kPush) << "the wall's torque at rest";
  const double ticks = window_s * 100.0;
  std::cout << "pidff: resting penetration " << x_rest << " rad (F/K " << kPush / kStiffness
            << "); at rest " << constants << " Set Constant Force and " << outputs
            << " output reports in " << ticks << " ticks\n";
  EXPECT_LT(static_cast<double>(outputs), ticks) << "an unchanged level sends nothing";
  EXPECT_EQ(board->allocated(), 0u) << "hid-pidff frees the effect hapticd erased";
  EXPECT_EQ(board->axis().motor(), 0.0);
  EXPECT_EQ(r.summary["direction_check"]["state"], "confirmed") << r.summary.dump();
  board.reset();
  EXPECT_TRUE(wait_until([&] {
    return !kernel_test::hidraw_listed(3, OpenFfboard::kVendor, OpenFfboard::kProduct, o.serial);
  }));
}

// Issue 32: a board whose firmware takes +sin (ArduinoJoystickWithFFBLibrary's, everything
// else OpenFFBoard's) behind hid-pidff with the same configuration: refused by the direction
// check before its wall acts, naming the setting that reverses the force.
TEST(OpenFfboardEvdev, ABoardWhoseForceIsReversedIsRefusedBeforeItsWallActs) {
  OpenFfboardOptions o;
  o.usb_report_rate = 4;
  o.serial = "ajwfl-evdev";
  o.force_sign = ForceSign::kArduinoJoystickWithFfbLibrary;
  auto board = std::make_unique<OpenFfboard>(o);
  ASSERT_TRUE(wait_until([&] {
    return kernel_test::hidraw_listed(3, OpenFfboard::kVendor, OpenFfboard::kProduct, o.serial);
  }));
  std::this_thread::sleep_for(std::chrono::seconds(1));  // hid-pidff's own probe at bind
  const HapticdRun r =
      run_hapticd(shipped("evdev.yaml"), evdev_sets(o.serial), {"--duration", "7"});
  EXPECT_EQ(r.status, 3) << r.faults() << "\n" << r.log;
  EXPECT_NE(r.faults().find("the direction check found the force reversed"), std::string::npos)
      << r.faults();
  EXPECT_NE(r.faults().find("device.evdev.direction_deg: 90 (it is 270)"), std::string::npos)
      << r.faults();
  EXPECT_EQ(r.summary["counters"]["loop"]["contact_ticks"], 0) << "no wall acted";
  EXPECT_EQ(board->axis().motor(), 0.0);
  std::cout << "pidff, +sin board: refused, direction check gain "
            << r.summary["direction_check"]["gain"] << "\n";
  board.reset();
  EXPECT_TRUE(wait_until([&] {
    return !kernel_test::hidraw_listed(3, OpenFfboard::kVendor, OpenFfboard::kProduct, o.serial);
  }));
}

}  // namespace
}  // namespace hapticd::reference
