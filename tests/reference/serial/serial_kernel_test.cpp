// hapticd run as a user runs it, against the reference serial devices behind a real ttyACM:
// each device on the gadget end (/dev/ttyGSn) of a USB CDC-ACM gadget on dummy_hcd, the
// kernel's own cdc_acm driver on the host end, in the kernel test machine. The Haply board's
// pantograph at rest where the wall's spring balances the hand, along a diagonal normal; the
// board unplugged mid-run; the streaming board silenced and its frames damaged. Each ends
// with zero force and the cause named.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>

#include "crc_stream_board.h"
#include "haply_board.h"
#include "hapticd_process.h"
#include "pty_pair.h"
#include "usb_acm_gadget.h"

namespace hapticd::reference {
namespace {

using namespace std::chrono_literals;

constexpr double kK = 50.0;    // N/m: at 100 Hz with one sample of delay the gate allows 85
constexpr double kPush = 0.5;  // N along the normal: F/K = 10 mm
const double kRoot2 = std::sqrt(2.0);

// The emulated machine's USB takes its time: 100 Hz, a declared latency of 10 ms (one
// sample), answers late now and then without a fault, a silent port after a second.
std::vector<std::string> guest_sets(const std::string& port) {
  return {"device.serial.port=" + port,     "loop.rate_hz=100",
          "loop.overrun_fault_streak=1000", "device.serial.latency_ms=10",
          "device.serial.liveness_ms=1000", "device.serial.answer_timeout_ms=5000",
          "safety.stale_fault_ticks=200"};
}

// The pantograph's: a wall the gate passes at 100 Hz.
std::vector<std::string> haply_sets(const std::string& port) {
  auto sets = guest_sets(port);
  sets.push_back("walls=[{point: [0.005, 0.075], normal: [1, 1], stiffness: 50, damping: 0}]");
  return sets;
}

// The gadget and its device end, raw.
struct Port {
  kernel_test::UsbAcmGadget gadget;
  int fd = -1;
  Port() {
    fd = ::open(gadget.device_path().c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error("open " + gadget.device_path());
    set_raw(fd);
  }
  ~Port() { ::close(fd); }
};

HaplyBoardOptions home_pose() {
  HaplyBoardOptions o;
  o.start_angles = {std::numbers::pi, 0.0};
  o.joints = {JointMechanics{5e-5, 0.004}, JointMechanics{5e-5, 0.004}};
  return o;
}

double penetration(Vec2 haply) {  // hapticd's origin is 10 mm right of Pantograph.cpp's
  return ((haply.x - 0.01 - 0.005) + (haply.y - 0.075)) / kRoot2;
}

std::string fault_text(const HapticdRun& r) { return r.summary["faults"].dump(); }

TEST(SerialAcm, TheHaplyPantographRestsWhereTheWallBalancesTheHand) {
  Port port;
  HaplyBoard board(port.fd, home_pose());
  board.start();
  const auto sets = haply_sets(port.gadget.host_path());
  double depth = 0.0;
  const HapticdRun r =
      run_hapticd(shipped("serial-haply-2diy.yaml"), sets, {"--duration", "40"}, [&](pid_t pid) {
        ASSERT_TRUE(wait_enabled()) << "hapticd never enabled output";
        board.plant().hand({kPush / kRoot2, kPush / kRoot2}, 1.0);
        std::this_thread::sleep_for(8s);
        depth = penetration(board.plant().effector());
        ::kill(pid, SIGTERM);
      });
  wait_until([&] { return board.motor_torque() == std::array<double, 2>{0.0, 0.0}; }, 2s);
  board.stop();
  ASSERT_EQ(r.status, 0) << r.faults() << "\n" << r.log;  // SIGTERM: a clean stop
  EXPECT_NEAR(depth, kPush / kK, 0.02 * kPush / kK) << "at rest within 2 % of F/K";
  std::printf("pantograph at rest %.4f mm along the normal (F/K %.4f mm)\n", depth * 1e3,
              kPush / kK * 1e3);
  EXPECT_EQ(board.motor_torque()[0], 0.0) << "zero torque left behind";
  EXPECT_EQ(board.motor_torque()[1], 0.0);
}

TEST(SerialAcm, UnpluggedMidRunTheRunEndsWithTheCauseNamed) {
  Port port;
  HaplyBoard board(port.fd, home_pose());
  board.start();
  const HapticdRun r =
      run_hapticd(shipped("serial-haply-2diy.yaml"), haply_sets(port.gadget.host_path()),
                  {"--duration", "20"}, [&](pid_t) {
                    std::this_thread::sleep_for(3s);
                    port.gadget.unplug();
                  });
  board.stop();
  EXPECT_EQ(r.status, 1) << r.log;
  // The hang-up, or the port taking nothing while it comes (cdc_acm's write finds no room for a
  // few ticks before the disconnect reaches the tty): either way the cause says unplugged.
  EXPECT_TRUE(fault_text(r).find("hung up") != std::string::npos ||
              fault_text(r).find("being unplugged") != std::string::npos)
      << fault_text(r);
  EXPECT_EQ(r.summary["device"]["final_command"], 0.0) << r.summary["device"].dump();
}

// The streaming board at 250 frames a second (what the emulated controller carries beside
// the host's frames), hapticd's wheel on its joint 0, pushed into the wall.
struct Stream {
  Port port;
  CrcStreamBoard board{port.fd, [] {
                         CrcStreamBoardOptions o;
                         o.rate_hz = 250;
                         o.joints = {JointMechanics{0.02, 0.02}, JointMechanics{0.02, 0.02}};
                         o.start_angles = {-0.1, 0.0};
                         return o;
                       }()};
  Stream() { board.start(); }
  HapticdRun run(const std::function<void()>& during) {
    auto sets = guest_sets(port.gadget.host_path());
    // At 100 Hz with one sample of delay the gate allows the wheel 1.2 N m/rad.
    sets.insert(sets.end(), {"safety.direction_check.mode=off", "wall.stiffness=1"});
    return run_hapticd(shipped("serial-stream.yaml"), sets, {"--duration", "40"}, [&](pid_t) {
      ASSERT_TRUE(wait_enabled());
      board.joint(0).hand(0.5, 0.01);
      std::this_thread::sleep_for(2s);
      during();
    });
  }
};

TEST(SerialAcm, AStreamThatFallsSilentFaultsWithZeroForce) {
  Stream s;
  const HapticdRun r = s.run([&] {
    EXPECT_GT(std::abs(s.board.commanded_torque()[0]), 0.1) << "the wall pushes";
    s.board.go_silent(true);
  });
  EXPECT_EQ(r.status, 1) << r.log;
  EXPECT_NE(fault_text(r).find("is silent"), std::string::npos) << fault_text(r);
  EXPECT_EQ(r.summary["device"]["final_command"], 0.0);
}

TEST(SerialAcm, DamagedFramesAreCountedThenAllDamagedIsSilence) {
  Stream s;
  const HapticdRun r = s.run([&] {
    s.board.corrupt_next(5);
    std::this_thread::sleep_for(1s);
    s.board.corrupt_next(1'000'000);
  });
  ASSERT_EQ(r.status, 1) << r.log;
  EXPECT_GE(r.summary["counters"]["serial"]["bad_check"].get<int>(), 5);
  EXPECT_NE(fault_text(r).find("all damaged"), std::string::npos) << fault_text(r);
}

}  // namespace
}  // namespace hapticd::reference
