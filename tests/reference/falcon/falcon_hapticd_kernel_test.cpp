// hapticd against the reference Falcon (falcon_firmware.h, falcon_mechanism.h) on the raw USB
// gadget in the kernel test machine, with the shipped config/falcon.yaml: the firmware loaded
// through a bootloader that ignores the first try, the grip homed by the test's hand (pulled out
// along +z, as libnifalcon's calibration asks of a person), then the box of six walls, each
// pushed into by the hand along its normal: at rest F/K deep, the force the motors apply the
// wall's. Then unplug, a hung firmware and a firmware that never answers. The emulated USB is
// slow: a liveness of 1 s and streaks of late ticks are the emulator's, as in the HID tests.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <thread>

#include "falcon_firmware.h"
#include "hapticd_process.h"
#include "raw_usb_ftdi.h"

namespace hapticd::reference::falcon {
namespace {

using namespace std::chrono_literals;

// The walls' stiffness here: the emulated USB answers a packet 5 to 20 ms late (several ticks,
// where hardware takes one), and the reference's own damping, 3 N s/m, must outweigh K times
// that delay for the loop to stay passive; 300 N/m (the shipped file's) does not, 100 does.
constexpr double kStiffness = 100.0;  // N/m
constexpr double kPush = 0.5;         // N: the hand's push along a wall's normal, F/K = 5 mm
constexpr const char* kSerial = "FHS00001";

std::string image_file() {
  const std::string path = "/tmp/hapticd-kt-falcon-image.bin";
  std::ofstream out(path, std::ios::binary);
  for (int i = 0; i < 7914; ++i) out.put(static_cast<char>((i * 131 + 17) >> 1));
  return path;
}

// hapticd opens the Falcon as it configures: the device is plugged in (the kernel has
// enumerated it) before, as a user's is.
bool plugged_in(const RawUsbFtdi& d) {
  // The host configured this device (not a stale entry of the last one, still going).
  return wait_until([&] { return d.configured() && listed_in_sysfs(); });
}

std::string notices(const HapticdRun& r) {
  return r.summary.is_object()
             ? r.summary["device"].value("notices", nlohmann::json::array()).dump()
             : "(no summary)";
}

double final_command(const HapticdRun& r) {
  return r.summary.is_object() ? r.summary["device"].value("final_command", -1.0) : -1.0;
}

std::vector<std::string> sets() {
  return {"device.falcon.firmware=" + image_file(), std::string("device.falcon.serial=") + kSerial,
          "device.falcon.liveness_ms=1000",         "device.falcon.homing_timeout_s=30",
          "loop.overrun_fault_streak=100000",       "safety.stale_fault_ticks=1000"};
}

// The test's hand on the reference's grip: a force it sets, and a spring to a line or a point
// it runs from its own thread (the reference has no gravity and no hand of its own).
class Hand {
 public:
  explicit Hand(RawUsbFtdi& d) : d_(d), t_([this] { run(); }) {}
  ~Hand() {
    stop_ = true;
    t_.join();
  }
  // A push `f` (N) plus a spring (k N/m, damped) toward `centre` across the push's direction.
  void set(const Vec3& f, const Vec3& centre, double k, double b = 5.0) {
    const std::lock_guard l(m_);
    f_ = f;
    centre_ = centre;
    k_ = k;
    b_ = b;
  }

 private:
  void run() {
    while (!stop_) {
      Vec3 f, c;
      double k = 0, b = 0;
      {
        const std::lock_guard l(m_);
        f = f_, c = centre_, k = k_, b = b_;
      }
      const double fn = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
      d_.with_firmware([&](FalconFirmware& fw) {
        const Vec3 x = fw.mechanism().position(), v = fw.mechanism().velocity();
        Vec3 h{};
        for (int i = 0; i < 3; ++i) {
          // The spring acts only across the push (along it the push alone, so at rest F is
          // exact); the hand's damping along every axis, as a person's arm has.
          const bool along = fn > 0 && std::abs(f[i]) > 1e-9;
          h[i] = f[i] + (along ? 0.0 : k * (c[i] - x[i])) - b * v[i];
        }
        fw.mechanism().set_hand_force(h);
        return 0;
      });
      std::this_thread::sleep_for(2ms);
    }
  }
  RawUsbFtdi& d_;
  std::mutex m_;
  Vec3 f_{}, centre_{0, 0, 0.11};
  double k_ = 0, b_ = 5.0;
  std::atomic<bool> stop_{false};
  std::thread t_;
};

// Once hapticd asks for homing: the grip pulled out along +z until every arm is homed, then
// brought back to the middle of the box, where the walls will be armed.
bool home(RawUsbFtdi& d, Hand& hand) {
  if (!wait_until(
          [&] { return d.with_firmware([](FalconFirmware& f) { return f.homing_mode(); }); }, 60s))
    return false;
  hand.set({0, 0, 1.0}, {0, 0, 0.11}, 0);
  if (!wait_until([&] { return d.with_firmware([](FalconFirmware& f) { return f.homed(); }) == 7; },
                  20s))
    return false;
  // A soft spring back to the middle and a firm grip: the reference's plant moves only while
  // packets flow, so it resumes after hapticd enables with the speed the pull gave it, which
  // the grip takes out at once (the box ends 15 mm beyond the arms' index), then slowly back.
  hand.set({0, 0, 0}, {0, 0, 0.11}, 10.0, 20.0);
  return true;
}

// Until hapticd has enabled output (the LED green) or ended.
bool output_on(RawUsbFtdi& d, pid_t pid) {
  return wait_until(
      [&] {
        return ended(pid) || d.with_firmware([](FalconFirmware& f) { return f.leds() == 0x2; });
      },
      30s);
}

struct Face {
  Vec3 point, normal;
};
const Face kFaces[] = {{{0.02, 0, 0.11}, {1, 0, 0}}, {{-0.02, 0, 0.11}, {-1, 0, 0}},
                       {{0, 0.02, 0.11}, {0, 1, 0}}, {{0, -0.02, 0.11}, {0, -1, 0}},
                       {{0, 0, 0.14}, {0, 0, 1}},    {{0, 0, 0.085}, {0, 0, -1}}};

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

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
  if (r.status != 0) {  // the ticks before the fault, for the record
    const std::string cmd =
        std::string(HAPTICD_BINARY) + " export /tmp/hapticd-kt-falcon.hlog | tail -25 >&2";
    EXPECT_EQ(std::system(cmd.c_str()), 0);
  }
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

// The exchange at 1 kHz for 60 s, the grip resting in the middle of the box: what a tick's
// round trip through the emulated USB costs (BENCHMARKS.md, "Falcon"), printed for the record;
// asserted only that the run holds (the emulator's timing is not the hardware's).
TEST(FalconHapticd, SixtySecondsAt1kHzForTheRecord) {
  RawUsbFtdi device;
  ASSERT_TRUE(plugged_in(device));
  Hand hand(device);
  const HapticdRun r = run_hapticd(shipped("falcon.yaml"), sets(), {"--duration", "60"},
                                   [&](pid_t) { ASSERT_TRUE(home(device, hand)); });
  ASSERT_EQ(r.status, 0) << r.log;
  ASSERT_TRUE(r.summary.is_object());
  const auto& loop = r.summary["counters"]["loop"];
  const auto& falcon = r.summary["counters"]["falcon"];
  const double ticks = r.summary.value("ticks", 0.0);
  std::cout << "60 s at 1 kHz: ticks " << ticks << ", missed_ticks "
            << loop.value("missed_ticks", -1) << ", overruns " << loop.value("overruns", -1)
            << ", stale_ticks " << loop.value("stale_ticks", -1) << ", packets in "
            << falcon.value("packets", -1) << ", out " << falcon.value("packets_sent", -1)
            << ", superseded " << falcon.value("superseded", -1) << ", skipped_bytes "
            << falcon.value("skipped_bytes", -1) << ", wake latency "
            << r.summary["wake_latency_us"].dump() << "\n";
  EXPECT_GT(ticks, 59000.0);
  EXPECT_EQ(falcon.value("malformed", -1), 0);
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
