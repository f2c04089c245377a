// hapticd run as a user runs it, against the reference serial devices on a pseudo-terminal (the
// device on the master, hapticd on /dev/pts/N): the Haply board under its pantograph at rest
// where the wall's spring balances the hand, and the CRC-framed streaming board silenced,
// corrupted, faulted and unplugged, each ending with zero force and the cause named. The same
// devices behind a real ttyACM are the kernel test machine's (serial_kernel_test.cpp).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>

#include "crc_stream_board.h"
#include "haply_board.h"
#include "hapticd_process.h"
#include "pty_pair.h"

namespace hapticd::reference {
namespace {

using namespace std::chrono_literals;

// The wall the pantograph meets: its normal along the diagonal, not an axis; K low enough that
// the encoders' counts (0.05 degree, 45 um at the arm) are a small part of F/K.
constexpr double kK = 100.0;                  // N/m
constexpr double kPoint[2] = {0.005, 0.075};  // m, hapticd's frame
const double kRoot2 = std::sqrt(2.0);

// A test machine running other tests beside this one holds the device's thread up for tens of
// milliseconds now and then: a silent port after 100 ms, not the example's 20.
const std::string kLoaded[2] = {"device.serial.liveness_ms=100", "safety.stale_fault_ticks=150"};

std::string wall_set() {
  return "walls=[{point: [0.005, 0.075], normal: [1, 1], stiffness: 100, damping: 0}]";
}

// Along the wall's normal, how deep the handle is: hapticd puts the origin between the motors,
// Pantograph.cpp on the first motor (d = 20 mm to its right).
double penetration(Vec2 haply) {
  const double x = haply.x - 0.01, y = haply.y;
  return ((x - kPoint[0]) + (y - kPoint[1])) / kRoot2;
}

TEST(SerialPty, TheHaplyPantographRestsWhereTheWallBalancesTheHand) {
  PtyPair pty = open_pty_pair();
  HaplyBoardOptions o;
  o.start_angles = {std::numbers::pi, 0.0};  // the home pose of the offsets the config sends
  o.joints = {JointMechanics{5e-5, 0.004}, JointMechanics{5e-5, 0.004}};
  HaplyBoard board(pty.master, o);
  board.start();
  const double push = 1.0;  // N along the normal
  double depth = 0.0;
  const HapticdRun r =
      run_hapticd(shipped("serial-haply-2diy.yaml"),
                  {"device.serial.port=" + pty.slave_path, wall_set(), kLoaded[0], kLoaded[1]},
                  {"--duration", "4"}, [&](pid_t) {
                    std::this_thread::sleep_for(500ms);
                    board.plant().hand({push / kRoot2, push / kRoot2}, 1.0);
                    std::this_thread::sleep_for(3s);
                    depth = penetration(board.plant().effector());
                  });
  // hapticd's stop frame is on its way: the board takes it within its next loops.
  wait_until([&] { return board.motor_torque() == std::array<double, 2>{0.0, 0.0}; }, 1s);
  board.stop();
  ASSERT_EQ(r.status, 0) << r.faults() << "\n" << r.log;
  EXPECT_TRUE(board.configured()) << "the startup frames set the board up";
  EXPECT_NEAR(depth, push / kK, 0.02 * push / kK) << "at rest within 2 % of F/K";
  std::printf("pantograph at rest %.4f mm along the normal (F/K %.4f mm)\n", depth * 1e3,
              push / kK * 1e3);
  EXPECT_EQ(r.summary["counters"]["serial"]["bad_check"], 0);
  EXPECT_EQ(board.motor_torque()[0], 0.0)
      << "zero torque left behind; the last torques received " << board.received_torque()[0] << ", "
      << board.received_torque()[1] << "; writes " << board.counters().writes;
  EXPECT_EQ(board.motor_torque()[1], 0.0);
}

// The streaming board with hapticd's one-joint wheel configuration on it (its joint 0).
struct StreamRig {
  PtyPair pty = open_pty_pair();
  CrcStreamBoard board{pty.master, [] {
                         CrcStreamBoardOptions o;
                         o.joints = {JointMechanics{0.02, 0.02}, JointMechanics{0.02, 0.02}};
                         o.start_angles = {-0.1, 0.0};
                         return o;
                       }()};
  StreamRig() { board.start(); }
  HapticdRun run(const std::function<void()>& during) {
    return run_hapticd(shipped("serial-stream.yaml"),
                       {"device.serial.port=" + pty.slave_path, "safety.direction_check.mode=off",
                        kLoaded[0], kLoaded[1]},
                       {"--duration", "6"}, [&](pid_t) {
                         ASSERT_TRUE(wait_enabled());
                         board.joint(0).hand(0.5, 0.01);  // into the wall at 0 rad
                         std::this_thread::sleep_for(600ms);
                         during();
                       });
  }
};

std::string fault_text(const HapticdRun& r) { return r.summary["faults"].dump(); }

TEST(SerialPty, AStreamThatFallsSilentFaultsWithZeroForce) {
  StreamRig rig;
  const HapticdRun r = rig.run([&] {
    ASSERT_GT(std::abs(rig.board.commanded_torque()[0]), 0.1) << "the wall pushes";
    rig.board.go_silent(true);
  });
  EXPECT_EQ(r.status, 1) << r.log;
  EXPECT_NE(fault_text(r).find("is silent"), std::string::npos) << fault_text(r);
  EXPECT_EQ(r.summary["device"]["final_command"], 0.0) << r.summary["device"].dump();
}

TEST(SerialPty, DamagedFramesAreCountedThenAllDamagedIsSilence) {
  StreamRig rig;
  const HapticdRun r = rig.run([&] {
    rig.board.corrupt_next(5);
    std::this_thread::sleep_for(300ms);
    rig.board.corrupt_next(1'000'000);
  });
  EXPECT_EQ(r.status, 1) << r.log;
  EXPECT_GE(r.summary["counters"]["serial"]["bad_check"].get<int>(), 5);
  EXPECT_NE(fault_text(r).find("all damaged"), std::string::npos) << fault_text(r);
  EXPECT_EQ(rig.board.counters().valid_frames > 0, true);
}

TEST(SerialPty, TheBoardsFaultBitFaultsTheRun) {
  StreamRig rig;
  const HapticdRun r = rig.run([&] { rig.board.set_fault(true); });
  EXPECT_EQ(r.status, 1) << r.log;
  EXPECT_NE(fault_text(r).find("reported a fault"), std::string::npos) << fault_text(r);
  EXPECT_EQ(rig.board.motor_torque()[0], 0.0);
}

TEST(SerialPty, UnpluggedMidRunFaultsWithTheCauseNamed) {
  StreamRig rig;
  const HapticdRun r = rig.run([&] {
    rig.board.stop();
    rig.pty.close_master();
  });
  EXPECT_EQ(r.status, 1) << r.log;
  EXPECT_NE(fault_text(r).find("serial port"), std::string::npos) << fault_text(r);
  EXPECT_EQ(r.summary["device"]["final_command"], 0.0) << r.summary["device"].dump();
}

}  // namespace
}  // namespace hapticd::reference
