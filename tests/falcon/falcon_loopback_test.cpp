// The Falcon driver against the simulated Falcon (sim/peers/falcon/) over the loopback
// socketpair, as `hapticd run --loopback` wires them: the firmware loaded and the grip homed
// before a position is read; the torque each arm feels is the one commanded, so the force at the
// grip is the one commanded in every direction; the one setting that reverses it; and each fault
// ending with zero torque and its cause named. The Falcon has no configuration of one joint, so
// these stand for the one-joint conformance suite (tests/drivers/conformance_test.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include <Eigen/LU>

#include "config/config_loader.h"
#include "falcon_image.h"
#include "kinematics/kinematics.h"
#include "sim/peers/falcon/falcon_peer.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers::falcon::testing {
namespace {

config::Config falcon_config(std::vector<std::string> sets) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/config/falcon.yaml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  sets.push_back("device.falcon.firmware=" + hapticd::testing::falcon_test_image());
  sets.push_back("loop.clock=freerun");
  sets.push_back("device.sim.operator.stiffness=1");  // a hand that barely holds the grip
  std::vector<config::Override> overrides;
  for (const std::string& s : sets) overrides.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), path, overrides, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

struct Loopback {
  explicit Loopback(std::vector<std::string> sets = {})
      : cfg(falcon_config(std::move(sets))),
        pair(wiring::find_driver("falcon").make_loopback(cfg)),
        runner(*pair.peer),
        device(std::move(pair.device), runner) {}
  ~Loopback() { device.close(); }
  sim::falcon::FalconPeer& peer() { return dynamic_cast<sim::falcon::FalconPeer&>(*pair.peer); }
  // One read, once the peer has answered what was sent (output off, read() itself sends the
  // packet the firmware answers; the paced device waits for the peer after a write only).
  IoStatus read() {
    runner.wait_idle();
    return device.read(std::span<PositionSample>(s));
  }
  // The torque each arm's motor puts on the mechanism, once the peer has taken what was sent.
  kinematics::Vec3 felt() {
    runner.wait_idle();
    const sim::Mechanism& m = peer().firmware().mechanism();
    return {m.held_torque(0), m.held_torque(1), m.held_torque(2)};
  }
  kinematics::Vec3 joints() const { return {s[0].position, s[1].position, s[2].position}; }

  config::Config cfg;
  wiring::Loopback pair;
  sim::PeerRunner runner;
  sim::PacedDevice device;
  std::array<PositionSample, 3> s{};
};

TEST(FalconLoopback, ConfigureLoadsAndHomesThenReadsTheArmsWhereTheyAre) {
  Loopback l;
  l.device.configure();
  EXPECT_TRUE(l.peer().homed());
  EXPECT_EQ(l.peer().loads_completed(), 1);
  l.read();
  ASSERT_EQ(l.read(), IoStatus::kOk);
  const sim::Mechanism& m = l.peer().firmware().mechanism();
  const double count = arm_angle(1) - arm_angle(0);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(l.s[j].position, m.plant().joint_positions()[j], count) << "joint " << j;
  }
}

TEST(FalconLoopback, TheForceAtTheGripIsTheOneCommandedWithin1PercentInEveryDirection) {
  Loopback l;
  l.device.configure();
  l.device.enable();
  const kinematics::Vec3 zero = kinematics::Vec3::Zero();
  ASSERT_EQ(l.device.write(std::span<const double>(zero.data(), 3)), IoStatus::kOk);
  ASSERT_EQ(l.read(), IoStatus::kOk);
  const kinematics::Pose p =
      kinematics::forward(l.cfg.device.kinematics, l.joints(),
                          kinematics::Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  ASSERT_EQ(p.status, kinematics::Status::kOk);
  int directions = 0;
  for (int a = -1; a <= 1; ++a) {
    for (int b = -1; b <= 1; ++b) {
      for (int c = -1; c <= 1; ++c) {
        if (a == 0 && b == 0 && c == 0) continue;
        const kinematics::Vec3 f = 2.0 * kinematics::Vec3(a, b, c).normalized();  // 2 N
        const kinematics::Vec3 tau = p.J.transpose() * f;
        ASSERT_EQ(l.device.write(std::span<const double>(tau.data(), 3)), IoStatus::kOk);
        const kinematics::Vec3 applied = p.J.transpose().inverse() * l.felt();
        EXPECT_LT((applied - f).norm(), 0.01 * f.norm())
            << "commanded " << f.transpose() << " N, applied " << applied.transpose();
        ++directions;
      }
    }
  }
  EXPECT_EQ(directions, 26);
}

TEST(FalconLoopback, TheCountsSettingsSignReversesTheTorqueEveryArmFeels) {
  const kinematics::Vec3 tau(0.1, -0.05, 0.02);
  for (const double k : {-10000.0, 10000.0}) {
    Loopback l({"device.falcon.counts_per_newton_metre=" + std::to_string(k)});
    l.device.configure();
    l.device.enable();
    ASSERT_EQ(l.device.write(std::span<const double>(tau.data(), 3)), IoStatus::kOk);
    const kinematics::Vec3 felt = l.felt();
    const double sign = k < 0 ? 1.0 : -1.0;  // the firmware's own scale is -10000
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(felt[j], sign * tau[j], 1e-4) << "k " << k;
  }
}

TEST(FalconLoopback, AnUnplugEndsWithZeroCommandedAndTheCauseNamed) {
  Loopback l;
  l.device.configure();
  l.device.enable();
  const kinematics::Vec3 tau(0.1, 0.1, 0.1);
  l.device.write(std::span<const double>(tau.data(), 3));
  ASSERT_TRUE(l.peer().inject(sim::PeerFault::kTransportFault));
  IoStatus r = IoStatus::kOk;
  for (int i = 0; i < 10 && r != IoStatus::kTransportFault; ++i) r = l.read();
  EXPECT_EQ(r, IoStatus::kTransportFault);
  EXPECT_EQ(l.device.describe_fault(), "falcon: the device is gone");
  for (std::size_t j = 0; j < 3; ++j) EXPECT_EQ(l.device.last_command(j), 0.0);
}

TEST(FalconLoopback, AHungFalconIsSilenceAfterLivenessAndItsMotorsGetZero) {
  Loopback l({"device.falcon.liveness_ms=20"});
  l.device.configure();
  l.device.enable();
  const kinematics::Vec3 tau(0.1, 0.1, 0.1);
  l.device.write(std::span<const double>(tau.data(), 3));
  ASSERT_GT(l.felt().norm(), 0.1);
  ASSERT_TRUE(l.peer().inject(sim::PeerFault::kStopAnswering));
  IoStatus r = IoStatus::kOk;
  for (int i = 0; i < 500 && r != IoStatus::kTransportFault; ++i) {
    r = l.read();
    if (r != IoStatus::kTransportFault) r = l.device.write(std::span<const double>(tau.data(), 3));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(r, IoStatus::kTransportFault);
  EXPECT_NE(l.device.describe_fault().find("no packet for 20 ms"), std::string::npos)
      << l.device.describe_fault();
  EXPECT_EQ(l.felt().norm(), 0.0) << "the hung firmware still took the zero packet";
}

TEST(FalconLoopback, ACorruptedPacketIsCountedAndTheNextOneRead) {
  Loopback l;
  l.device.configure();
  l.read();
  l.peer().corrupt_next_packet();
  for (int i = 0; i < 5; ++i) l.read();
  EXPECT_EQ(l.read(), IoStatus::kOk);
  for (const base::Counter& c : l.device.counters()) {
    if (c.name() == "malformed") {
      EXPECT_EQ(c.value(), 1u);
    }
  }
}

}  // namespace
}  // namespace hapticd::drivers::falcon::testing
