// Two CiA 402 reference drives (tests/reference/can, written from CiA 301/402 and CANopenNode's
// rules, sharing no code with the driver) on one socketpair bus as the two joints of one
// device (device.can.nodes, config/can-gantry.yaml): each joint's torque reaches its own drive,
// one SYNC per tick reaches both, a normal stop keeps SYNC going until both watch it no more
// (no EMCY), and an EMCY of either drive ends with both switched off and the cause naming that
// node.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <string>
#include <thread>

#include "reference/can/cia402_drive.h"
#include "reference_rig.h"

namespace hapticd::drivers::can::testing {
namespace {

using reference::Cia402Behaviour;
using reference::Cia402Drive;

// Both drives on one bus: every frame of the master reaches each, both answer.
class TwoDriveBus final : public reference::ReferenceDevice {
 public:
  TwoDriveBus(Cia402Drive& a, Cia402Drive& b) : a_(a), b_(b) {}
  void on_frame(const reference::Frame& f, std::int64_t now_ns,
                std::vector<reference::Frame>& out) override {
    a_.on_frame(f, now_ns, out);
    b_.on_frame(f, now_ns, out);
  }
  void on_clock(std::int64_t now_ns, std::vector<reference::Frame>& out) override {
    a_.on_clock(now_ns, out);
    b_.on_clock(now_ns, out);
  }

 private:
  Cia402Drive& a_;
  Cia402Drive& b_;
};

Cia402Behaviour node_behaviour(std::uint8_t node) {
  Cia402Behaviour b;
  b.node = node;
  return b;
}

// A cycle long enough that the drives' 1.5-cycle SYNC watch and heartbeat consumer judge the
// driver, not a loaded host (as can_reference_cia402_test's slow configuration).
config::Config slow_gantry() {
  return load_example(
      "can-gantry.yaml",
      {"loop.rate_hz=20", "device.can.cia402.master_heartbeat_ms=100",
       "device.can.cia402.drive_watchdog_ms=1000", "device.can.heartbeat_timeout_ms=1000"},
      false);
}

// Ticks both joints for `ms` at the configured period, as the loop would; the first fault
// status, or kOk. `ticks` counts the writes.
IoStatus run_joints(ReferenceRig& rig, std::array<double, 2> forces, int ms,
                    std::array<PositionSample, 2>& last, int& ticks) {
  RealTime rt;
  const auto period =
      std::chrono::nanoseconds(static_cast<std::int64_t>(rig.cfg.loop.sample_period_s() * 1e9));
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  auto next = std::chrono::steady_clock::now();
  std::array<PositionSample, 2> s{};
  while (std::chrono::steady_clock::now() < end) {
    IoStatus r = rig.device->read(s);
    if (r == IoStatus::kOk) last = s;
    if (r != IoStatus::kTransportFault && r != IoStatus::kDeviceFault) {
      r = rig.device->write(forces);
      ++ticks;
    }
    if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return r;
    next += period;
    if (next >= end) break;  // a stop that follows comes within the cycle, as the loop's
    std::this_thread::sleep_until(next);
  }
  return IoStatus::kOk;
}

TEST(CanReferenceNodes, EachJointsTorqueReachesItsOwnDriveWithOneSyncPerTick) {
  Cia402Drive x(node_behaviour(1), damped_axis(), reference::monotonic_ns());
  Cia402Drive y(node_behaviour(2), damped_axis(), reference::monotonic_ns());
  TwoDriveBus bus(x, y);
  ReferenceRig rig(slow_gantry(), bus);
  rig.device->configure();
  rig.device->enable();
  EXPECT_TRUE(x.torque_on());
  EXPECT_TRUE(y.torque_on());
  std::array<PositionSample, 2> last{};
  int ticks = 0;
  ASSERT_EQ(run_joints(rig, {1.0, -2.0}, 1000, last, ticks), IoStatus::kOk)
      << rig.device->describe_fault();
  EXPECT_NEAR(x.motor_force_n(), 1.0, 1e-9) << "joint 0's force at node 1";
  EXPECT_NEAR(y.motor_force_n(), -2.0, 1e-9) << "joint 1's force at node 2";
  // 1 N and -2 N against 10 N s/m from -0.02 m: each axis moved its own way (0.1 and -0.2 m/s),
  // and each joint reads its own.
  EXPECT_GT(last[0].position, 0.0);
  EXPECT_LT(last[1].position, -0.1);
  EXPECT_NEAR((last[1].position + 0.02) / (last[0].position + 0.02), -2.0, 0.1)
      << "joint 1 moved twice as far as joint 0, the other way";
  sleep_ms(10);  // the last tick's frames reach the drives
  const std::int64_t stop_ns = reference::monotonic_ns();
  rig.device->disable();
  EXPECT_FALSE(x.torque_on());
  EXPECT_FALSE(y.torque_on());
  sleep_ms(200);  // 4 cycles: a SYNC or heartbeat watch still on would have fired
  rig.runner->stop();
  EXPECT_EQ(x.object(0x1006, 0), 0u) << "node 1's SYNC watch switched off by the stop";
  EXPECT_EQ(y.object(0x1006, 0), 0u) << "node 2's";
  int syncs = 0;
  int rpdos_x = 0;
  int rpdos_y = 0;
  for (const reference::LoggedFrame& l : rig.runner->log()) {
    if (l.sent && (l.frame.id == 0x081 || l.frame.id == 0x082)) {
      EXPECT_EQ(l.frame.u16(0), 0) << "an EMCY of node " << (l.frame.id - 0x80)
                                   << " (0x8100: SYNC lost, 0x8130: heartbeat lost)";
    }
    if (l.sent || l.time_ns >= stop_ns) continue;
    syncs += l.frame.id == 0x080 ? 1 : 0;
    rpdos_x += l.frame.id == 0x201 ? 1 : 0;
    rpdos_y += l.frame.id == 0x202 ? 1 : 0;
  }
  EXPECT_EQ(syncs, ticks) << "one SYNC per tick for both drives";
  EXPECT_EQ(rpdos_x, ticks);
  EXPECT_EQ(rpdos_y, ticks);
}

// An EMCY of either drive: the device faults, zero torque goes to both, the stop switches both
// off, and the cause names the node.
void expect_emcy_of(int faulty) {
  SCOPED_TRACE("node " + std::to_string(faulty));
  Cia402Drive x(node_behaviour(1), damped_axis(), reference::monotonic_ns());
  Cia402Drive y(node_behaviour(2), damped_axis(), reference::monotonic_ns());
  TwoDriveBus bus(x, y);
  ReferenceRig rig(slow_gantry(), bus);
  rig.device->configure();
  rig.device->enable();
  std::array<PositionSample, 2> last{};
  int ticks = 0;
  ASSERT_EQ(run_joints(rig, {1.5, 1.5}, 300, last, ticks), IoStatus::kOk)
      << rig.device->describe_fault();
  EXPECT_NEAR(x.motor_force_n(), 1.5, 1e-9);
  EXPECT_NEAR(y.motor_force_n(), 1.5, 1e-9);
  (faulty == 1 ? x : y).inject_fault(0x2310);
  EXPECT_EQ(run_joints(rig, {1.5, 1.5}, 2000, last, ticks), IoStatus::kDeviceFault);
  Cia402Drive& healthy = faulty == 1 ? y : x;
  EXPECT_TRUE(eventually([&] { return healthy.motor_force_n() == 0.0; }))
      << "zero on the healthy node from the fault on";
  const std::string why = rig.device->describe_fault();
  EXPECT_NE(why.find("cia402 node " + std::to_string(faulty) + " sent EMCY 0x2310"),
            std::string::npos)
      << why;
  rig.device->disable();
  EXPECT_FALSE(x.torque_on());
  EXPECT_FALSE(y.torque_on());
  EXPECT_EQ(x.motor_force_n(), 0.0);
  EXPECT_EQ(y.motor_force_n(), 0.0);
}

TEST(CanReferenceNodes, AnEmcyOfEitherDriveSwitchesBothOffAndNamesIt) {
  expect_emcy_of(1);
  expect_emcy_of(2);
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
