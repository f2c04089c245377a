// hapticd against the reference Falcon (falcon_firmware.h, falcon_mechanism.h) on the raw USB
// gadget in the kernel test machine, with the shipped config/falcon.yaml: the firmware loaded
// through a bootloader that ignores the first try, the grip homed by the test's hand (pulled out
// along +z, as libnifalcon's calibration asks of a person), then the box of six walls, each
// pushed into by the hand along its normal: at rest F/K deep, the force the motors apply the
// wall's. Then unplug, a hung firmware and a firmware that never answers. The emulated USB is
// slow: a liveness of 1 s and streaks of late ticks are the emulator's, as in the HID tests.
#include <gtest/gtest.h>

#include <iostream>
#include <thread>

#include "falcon_firmware.h"
#include "falcon_rig.h"

namespace hapticd::reference::falcon {
namespace {

using namespace std::chrono_literals;

// The walls' stiffness here: the emulated USB answers a packet 5 to 20 ms late (several ticks,
// where hardware takes one), and the reference's own damping, 3 N s/m, must outweigh K times
// that delay for the loop to stay passive; 300 N/m (the shipped file's) does not, 100 does.
constexpr double kStiffness = 100.0;  // N/m
constexpr double kPush = 0.5;         // N: the hand's push along a wall's normal, F/K = 5 mm

// The emulated USB is slow, so the bounds that catch a stalled exchange are the emulator's
// (the timed machine runs the shipped ones: falcon_timed_kernel_test.cpp). The loop's stale
// bound is the longer, so a hung device is named by the driver's own liveness watch.
std::vector<std::string> sets() {
  std::vector<std::string> v = reference_sets();
  v.insert(v.end(), {"device.falcon.liveness_ms=1000", "device.falcon.homing_timeout_s=30",
                     "loop.overrun_fault_streak=100000", "safety.stale_fault_ticks=2000"});
  return v;
}

struct Face {
  Vec3 point, normal;
};
const Face kFaces[] = {{{0.02, 0, 0.11}, {1, 0, 0}}, {{-0.02, 0, 0.11}, {-1, 0, 0}},
                       {{0, 0.02, 0.11}, {0, 1, 0}}, {{0, -0.02, 0.11}, {0, -1, 0}},
                       {{0, 0, 0.14}, {0, 0, 1}},    {{0, 0, 0.085}, {0, 0, -1}}};

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

std::string notices(const HapticdRun& r) {
  return r.summary.is_object()
             ? r.summary["device"].value("notices", nlohmann::json::array()).dump()
             : "(no summary)";
}

double final_command(const HapticdRun& r) {
  return r.summary.is_object() ? r.summary["device"].value("final_command", -1.0) : -1.0;
}

std::vector<std::string> soft_walls() {
  std::vector<std::string> v = sets();
  for (int i = 0; i < 6; ++i) {
    v.push_back("walls[" + std::to_string(i) + "].stiffness=" + std::to_string(kStiffness));
  }
  return v;
}

// Items of issue 38: loaded on the second try, homed, each face F/K deep at rest, the force
// the motors apply the one hapticd commands (the wall's, -F along the normal) within 1 %.
TEST(FalconHapticd, LoadedHomedAndEachWallHoldsTheHandFOverKDeep) {
  FirmwareOptions o;
  o.fail_first_try = true;
  RawUsbFtdi device(o);
  ASSERT_TRUE(plugged_in(device));
  Hand hand(device);
  std::vector<double> depth(6, 0.0);
  std::vector<Vec3> applied(6);
  const HapticdRun r = run_hapticd(
      shipped("falcon.yaml"), soft_walls(),
      {"--duration", "40", "--log", "/tmp/hapticd-kt-falcon.hlog"}, [&](pid_t pid) {
        ASSERT_TRUE(home(device, hand)) << "never homed";
        ASSERT_TRUE(output_on(device, pid)) << "output never enabled";
        hand.set({0, 0, 0}, {0, 0, 0.11}, 60.0);
        std::this_thread::sleep_for(3s);  // back in the middle of the box
        for (std::size_t i = 0; i < 6; ++i) {
          const Face& face = kFaces[i];
          const Vec3 f{kPush * face.normal[0], kPush * face.normal[1], kPush * face.normal[2]};
          hand.set(f, {0, 0, 0.11}, 60.0);
          std::this_thread::sleep_for(3s);
          ASSERT_FALSE(ended(pid)) << "hapticd ended while the hand pushed face " << i;
          device.with_firmware([&](FalconFirmware& fw) {
            const Vec3 x = fw.mechanism().position();
            depth[i] = dot({x[0] - face.point[0], x[1] - face.point[1], x[2] - face.point[2]},
                           face.normal);
            applied[i] = fw.mechanism().motor_force();
            return 0;
          });
          hand.set({0, 0, 0}, {0, 0, 0.11}, 60.0);
          std::this_thread::sleep_for(1s);
        }
        ::kill(pid, SIGTERM);
      });
  EXPECT_EQ(r.status, 0) << r.log;
  if (r.status != 0) print_log_end("/tmp/hapticd-kt-falcon.hlog", 25);  // the ticks before it
  EXPECT_NE(notices(r).find("try 2: loaded"), std::string::npos) << notices(r);
  for (std::size_t i = 0; i < 6; ++i) {
    const Vec3& n = kFaces[i].normal;
    EXPECT_NEAR(depth[i], kPush / kStiffness, 0.02 * kPush / kStiffness) << "face " << i;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(applied[i][k], -kPush * n[k], 0.01 * kPush) << "face " << i << " axis " << k;
    }
    std::cout << "face " << i << ": " << depth[i] * 1e3 << " mm deep (F/K "
              << kPush / kStiffness * 1e3 << "), motors apply (" << applied[i][0] << ", "
              << applied[i][1] << ", " << applied[i][2] << ") N\n";
  }
  EXPECT_EQ(device.error(), "");
}

// A crash while the hand pushes into a wall: the crash handler's zero packet reaches the
// firmware through the descriptor libusb drives (an ioctl: libusb itself is not
// async-signal-safe), and the motors let go. Before, the Falcon kept the wall's last force.
TEST(FalconHapticd, ACrashWhileAWallPushesLeavesTheMotorsAtZero) {
  RawUsbFtdi device;
  ASSERT_TRUE(plugged_in(device));
  Hand hand(device);
  Vec3 before{}, after{};
  const HapticdRun r =
      run_hapticd(shipped("falcon.yaml"), soft_walls(), {"--duration", "40"}, [&](pid_t pid) {
        ASSERT_TRUE(home(device, hand));
        ASSERT_TRUE(output_on(device, pid));
        hand.set({0, 0, 0}, {0, 0, 0.11}, 60.0);
        std::this_thread::sleep_for(3s);  // back in the middle of the box
        hand.set({kPush, 0, 0}, {0, 0, 0.11}, 60.0);
        std::this_thread::sleep_for(3s);  // at rest in the +x wall
        ASSERT_FALSE(ended(pid)) << "hapticd ended while the hand pushed";
        before =
            device.with_firmware([](FalconFirmware& f) { return f.mechanism().motor_force(); });
        ::kill(pid, SIGSEGV);
        ASSERT_TRUE(wait_until([&] { return ended(pid); }, 10s));
        // The packet the host's transfer handed over reaches the firmware on its own thread.
        wait_until(
            [&] {
              after = device.with_firmware(
                  [](FalconFirmware& f) { return f.mechanism().motor_force(); });
              return after == Vec3{};
            },
            2s);
      });
  EXPECT_EQ(r.status, 128 + SIGSEGV) << r.log;
  EXPECT_NEAR(before[0], -kPush, 0.05 * kPush) << "the wall held the hand before the crash";
  for (int k = 0; k < 3; ++k) EXPECT_EQ(after[k], 0.0) << "the motors after the crash, axis " << k;
}

// Unplugged while rendering, hung, and a firmware that never answers: each ends the run with
// zero commanded and the cause named.
TEST(FalconHapticd, UnplugHangAndASilentFirmwareEachEndWithTheCauseNamed) {
  for (const char* fault : {"unplug", "hang"}) {
    SCOPED_TRACE(fault);
    RawUsbFtdi device;
    ASSERT_TRUE(plugged_in(device));
    Hand hand(device);
    const HapticdRun r =
        run_hapticd(shipped("falcon.yaml"), sets(), {"--duration", "40"}, [&](pid_t pid) {
          ASSERT_TRUE(home(device, hand));
          ASSERT_TRUE(output_on(device, pid));
          std::this_thread::sleep_for(1s);
          if (std::string(fault) == "unplug") {
            device.unplug();
          } else {
            device.with_firmware([](FalconFirmware& f) {
              f.hang();
              return 0;
            });
          }
          ASSERT_TRUE(wait_until([&] { return ended(pid); }, 10s)) << "the run went on";
        });
    EXPECT_EQ(r.status, 1) << r.log;
    const std::string cause =
        std::string(fault) == "unplug" ? "falcon: the device is gone" : "no packet for 1000 ms";
    EXPECT_NE(r.log.find(cause), std::string::npos) << r.log;
    EXPECT_EQ(final_command(r), 0.0);
  }
  FirmwareOptions o;
  o.silent_firmware = true;
  RawUsbFtdi device(o);
  ASSERT_TRUE(plugged_in(device));
  const HapticdRun r = run_hapticd(shipped("falcon.yaml"), sets(), {"--duration", "40"});
  EXPECT_EQ(r.status, 4) << r.log;
  EXPECT_NE(r.log.find("the firmware did not load in 3 tries"), std::string::npos) << r.log;
  EXPECT_NE(r.log.find("the firmware never answered a packet"), std::string::npos) << r.log;
}

}  // namespace
}  // namespace hapticd::reference::falcon
