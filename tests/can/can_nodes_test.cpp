// Several CAN nodes as one device of several joints (device.can.nodes, issue 35 part 6): the
// section and its errors, the bus load of every node and its refusal, and the device against
// one simulated drive per node on one bus (can_nodes_bus.h): each joint read and written
// through its own node, one SYNC per tick for the bus, a fault of either node ending with zero
// torque on both and its cause naming that node, and no allocation in read/write.
#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include "can_nodes_bus.h"
#include "drivers/can/can_bus_load.h"

namespace hapticd::drivers::can::testing {
namespace {

using sim::CanPeerFault;
using sim::PeerFault;

config::Config gantry(std::vector<std::string> sets = {}) {
  return load_example("can-gantry.yaml", std::move(sets));
}

// The ODrive axes of the same gantry.
config::Config odrive_gantry(std::vector<std::string> sets = {}) {
  std::vector<std::string> all = {"device.can.profile=odrive", "device.can.cia402=null"};
  all.insert(all.end(), sets.begin(), sets.end());
  return gantry(all);
}

// Every message the loader gave for `sets` over the gantry, or "" when it loaded.
std::string gantry_errors(std::vector<std::string> sets) {
  try {
    gantry(std::move(sets));
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const std::string& m : e.messages()) all += m + "\n";
    return all;
  }
  return "";
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CanNodesSection, JointIIsNodesIWithItsOwnTransmissionOrTheSections) {
  const config::Config cfg =
      gantry({"device.can.nodes=[{node_id: 5}, {node_id: 3, "
              "torque_per_force: -0.02, max_torque: 0.05}]"});
  const CanSettings& s = can_settings(cfg);  // the configuration keeps the settings
  ASSERT_EQ(s.nodes.size(), 2u);
  EXPECT_EQ(s.nodes[0].node_id, 5);
  EXPECT_EQ(s.nodes[0].torque_per_force, 0.01) << "the section's";
  EXPECT_EQ(s.nodes[0].max_torque, 0.1);
  EXPECT_EQ(s.nodes[1].node_id, 3);
  EXPECT_EQ(s.nodes[1].torque_per_force, -0.02) << "its own";
  EXPECT_EQ(s.nodes[1].position_per_unit, 1e-5);
  EXPECT_EQ(s.nodes[1].max_torque, 0.05);
  const config::Config single = load_example("can-cia402.yaml");
  const CanSettings& one = can_settings(single);
  ASSERT_EQ(one.nodes.size(), 1u) << "node_id still means one node";
  EXPECT_EQ(one.nodes[0].node_id, 1);
  EXPECT_EQ(one.nodes[0].torque_per_force, 0.01);
}

TEST(CanNodesSection, NodesAndNodeIdRefuseEachOtherAndDuplicatesAreNamed) {
  std::string e = gantry_errors({"device.can.node_id=3"});
  EXPECT_TRUE(has(e, "can-gantry.yaml:")) << e;
  EXPECT_TRUE(has(e, ": device.can.nodes: refuses device.can.node_id beside it")) << e;
  e = gantry_errors({"device.can.nodes=[{node_id: 2}, {node_id: 2}]"});
  EXPECT_TRUE(has(e,
                  "device.can.nodes[1].node_id: node 2 twice: device.can.nodes[0] and "
                  "device.can.nodes[1]"))
      << e;
  e = gantry_errors({"device.can.nodes=[]"});
  EXPECT_TRUE(has(e, "device.can.nodes: must be a list of 1 to 3 nodes")) << e;
  e = gantry_errors({"device.can.nodes=[{node_id: 1}, {node_id: 2}, {node_id: 3}, {node_id: 4}]"});
  EXPECT_TRUE(has(e, "got 4 entries")) << e;
  e = gantry_errors({"device.can.nodes=[{node_id: 1}, {torque_per_force: 1}]"});
  EXPECT_TRUE(has(e, "device.can.nodes[1].node_id: missing")) << e;
  e = gantry_errors({"device.can.nodes=[{node_id: 1}, {node_id: 200}]"});
  EXPECT_TRUE(has(e, "device.can.nodes[1].node_id: must be in 1..127")) << e;
  e = gantry_errors({"device.can.nodes=[{node_id: 1}, {node_id: 2, torque_per_force: 0}]"});
  EXPECT_TRUE(has(e, "device.can.nodes[1].torque_per_force: must not be 0")) << e;
  e = gantry_errors({"device.can.nodes=[{node_id: 1}, {node_id: 2, gear: 3}]"});
  EXPECT_TRUE(has(e, "device.can.nodes[1].gear: unknown key")) << e;
  e = gantry_errors({"device.can.nodes=[{node_id: 1}]"});
  EXPECT_TRUE(has(e,
                  "device.can: 1 node(s) drive 1 joint(s), but device.kinematics (cartesian) "
                  "has 2"))
      << e;
}

TEST(CanNodesBusLoad, EveryNodeCountsAndTheBusHasOneSync) {
  CanSettings s = can_settings(gantry());
  s.cia402.master_heartbeat_ms = 0;
  const BusLoad two = bus_load(s, 1000.0);
  // One SYNC 55 + two RPDOs 2 x 95 + two TPDOs 2 x 115 = 475 bits a tick, two heartbeats.
  EXPECT_NEAR(two.bits_per_tick, 475 + 2 * 0.65, 1e-9);
  EXPECT_NEAR(two.frames_per_tick, 5.02, 1e-9);
  s.nodes.resize(1);
  EXPECT_NEAR(bus_load(s, 1000.0).bits_per_tick, 265 + 0.65, 1e-9);
}

TEST(CanNodesBusLoad, ABusThatCannotCarryATickIsRefusedSayingWhatWouldFit) {
  // Three ODrive axes at 4 kHz on 250 kbit/s: 3 x (95 + 55 + 135) bits a tick, 1370 % of it.
  const std::vector<std::string> sets = {
      "loop.rate_hz=4000",
      "device.can.bitrate=250000",
      "device.kinematics={kind: cartesian, joints: 3, scale: [1, 1, 1], sign: [1, 1, 1]}",
      "walls=[{point: [0.02, 0.02, 0], normal: [1, 1, 0], stiffness: 100}]",
      "device.can.nodes=[{node_id: 1}, {node_id: 2}, {node_id: 3}]",
      "device.sim=null"};  // the example's hand is in the plane
  std::string e;
  try {
    odrive_gantry(sets);
  } catch (const config::ConfigError& error) {
    for (const std::string& m : error.messages()) e += m + "\n";
  }
  EXPECT_TRUE(has(e, "can-gantry.yaml:")) << e;
  EXPECT_TRUE(has(e,
                  ": device.can: the bus cannot carry one tick's frames within one period: 3 "
                  "node(s) need "))
      << e;
  EXPECT_TRUE(has(e, "of 250000 bit/s at 4000 Hz (9.0")) << e;
  EXPECT_TRUE(has(e, "What would fit: loop.rate_hz at most 287 Hz")) << e;
  EXPECT_TRUE(has(e, "fewer nodes on this bus")) << e;
  // The rate named is the highest that fits (a slower tick carries more of the heartbeats).
  std::vector<std::string> at = sets;
  at[0] = "loop.rate_hz=287";
  EXPECT_LE(bus_load(can_settings(odrive_gantry(at)), 287.0).load, 1.0);
  at[0] = "loop.rate_hz=288";
  EXPECT_THROW(odrive_gantry(at), config::ConfigError);
  // At 1 kHz two axes fit, above bus_load_warn: a warning, not a refusal.
  const config::Config fits =
      odrive_gantry({"device.can.bitrate=1000000", "device.can.nodes=[{node_id: 1}, {node_id: 2}]",
                     "device.can.bus_load_warn=0.5"});
  std::string notes;
  for (const std::string& line : wiring::find_driver("can").notes(fits)) notes += line + "\n";
  EXPECT_TRUE(has(notes, "warning: can bus load 57.")) << notes;
  EXPECT_TRUE(has(notes, "Set_Input_Torque x2")) << notes;
}

// Joint i's force reaches node i's drive and node i's position is joint i's sample; one
// SYNC per tick goes on the wire for both; read and write allocate nothing.
TEST(CanNodesLoopback, TwoNodesAreReadAndWrittenWithOneSyncPerTick) {
  NodesRig rig(gantry({"device.sim=null"}));  // no hand: the joints move with their forces
  rig.device->configure();
  EXPECT_EQ(rig.device->info().joints, 2u);
  EXPECT_TRUE(has(rig.device->info().description, "cia402 node 1"))
      << rig.device->info().description;
  EXPECT_TRUE(has(rig.device->info().description, "cia402 node 2"))
      << rig.device->info().description;
  rig.device->enable();
  EXPECT_TRUE(rig.hub->drive(0).output_on());
  EXPECT_TRUE(rig.hub->drive(1).output_on());
  const std::uint64_t syncs_before = rig.hub->frames_from_master(0x080);
  const std::array<double, 2> forces = {1.0, -2.0};
  std::array<PositionSample, 2> s{};
  constexpr int kTicks = 400;
  const NodesRig::Run run = rig.ticks(forces, s, kTicks);
  ASSERT_EQ(run.failure, IoStatus::kOk) << rig.device->describe_fault();
  EXPECT_EQ(run.allocations, 0u) << "read/write of two nodes over " << kTicks << " ticks";
  EXPECT_GE(run.fresh, kTicks - 1) << "every TPDO answers its SYNC (the first read precedes any)";
  EXPECT_EQ(rig.hub->frames_from_master(0x080) - syncs_before, static_cast<std::uint64_t>(kTicks))
      << "one SYNC per tick for the whole bus";
  EXPECT_EQ(rig.hub->frames_from_master(0x201), rig.hub->frames_from_master(0x202))
      << "one RPDO per node";
  EXPECT_DOUBLE_EQ(rig.hub->drive(0).applied_force(), 1.0) << "joint 0's force at node 1";
  EXPECT_DOUBLE_EQ(rig.hub->drive(1).applied_force(), -2.0) << "joint 1's force at node 2";
  // Each joint moved with its own force: joint 0 forward, joint 1 back.
  EXPECT_GT(s[0].position, 0.0);
  EXPECT_LT(s[1].position, 0.0);
  rig.device->disable();
  EXPECT_FALSE(rig.hub->drive(0).output_on());
  EXPECT_FALSE(rig.hub->drive(1).output_on());
}

// Runs the two nodes at a force on each until the device faults; the status.
IoStatus run_until_fault(NodesRig& rig, int limit) {
  const std::array<double, 2> forces = {1.5, 1.5};
  std::array<PositionSample, 2> s{};
  for (int i = 0; i < limit; ++i) {
    const IoStatus r = rig.tick(forces, s);
    if (r == IoStatus::kDeviceFault || r == IoStatus::kTransportFault) return r;
  }
  return IoStatus::kOk;
}

// A fault of either node faults the device: zero on both joints from the next write, both
// drives switched off by the stop, the cause naming the node.
void expect_fault_of(const config::Config& cfg, std::size_t node, bool heartbeat,
                     const std::string& cause) {
  SCOPED_TRACE("node index " + std::to_string(node));
  NodesRig rig(cfg);
  rig.device->configure();
  rig.device->enable();
  ASSERT_EQ(run_until_fault(rig, 20), IoStatus::kOk) << rig.device->describe_fault();
  EXPECT_NE(rig.hub->drive(0).applied_force(), 0.0);
  EXPECT_NE(rig.hub->drive(1).applied_force(), 0.0);
  if (heartbeat) {
    ASSERT_TRUE(rig.hub->drive(node).inject_can(CanPeerFault::kStopHeartbeat));
  } else {
    ASSERT_TRUE(rig.hub->drive(node).inject(PeerFault::kDeviceFault));
  }
  EXPECT_EQ(run_until_fault(rig, 2000), IoStatus::kDeviceFault);
  EXPECT_EQ(rig.device->state(), DeviceState::kFaulted);
  const std::array<double, 2> forces = {1.5, 1.5};
  std::array<PositionSample, 2> s{};
  rig.tick(forces, s);  // the loop keeps writing; the device passes zero on every joint
  const std::size_t other = 1 - node;
  EXPECT_EQ(rig.hub->drive(other).applied_force(), 0.0) << "the healthy node's torque too";
  const std::string why = rig.device->describe_fault();
  EXPECT_TRUE(has(why, cause)) << why;
  rig.device->disable();
  EXPECT_FALSE(rig.hub->drive(0).output_on());
  EXPECT_FALSE(rig.hub->drive(1).output_on());
  EXPECT_EQ(rig.hub->drive(0).applied_force(), 0.0);
  EXPECT_EQ(rig.hub->drive(1).applied_force(), 0.0);
}

TEST(CanNodesLoopback, AnEmcyOfEitherNodeZeroesBothAndNamesIt) {
  expect_fault_of(gantry(), 0, false, "cia402 node 1 sent EMCY");
  expect_fault_of(gantry(), 1, false, "cia402 node 2 sent EMCY");
}

TEST(CanNodesLoopback, AHeartbeatLostOnEitherNodeZeroesBothAndNamesIt) {
  expect_fault_of(gantry(), 0, true, "cia402 node 1: no heartbeat (0x701)");
  expect_fault_of(gantry(), 1, true, "cia402 node 2: no heartbeat (0x702)");
}

TEST(CanNodesLoopback, TwoOdriveAxesEachWithTheirOwnIdsAndRequests) {
  NodesRig rig(odrive_gantry({"device.sim=null"}));
  rig.device->configure();
  EXPECT_EQ(rig.device->info().joints, 2u);
  rig.device->enable();
  const std::array<double, 2> forces = {-1.0, 2.0};
  std::array<PositionSample, 2> s{};
  constexpr int kTicks = 300;
  const std::uint64_t requests1 = rig.hub->frames_from_master(1 << 5 | 0x09);
  const std::uint64_t requests2 = rig.hub->frames_from_master(2 << 5 | 0x09);
  const NodesRig::Run run = rig.ticks(forces, s, kTicks);
  ASSERT_EQ(run.failure, IoStatus::kOk) << rig.device->describe_fault();
  EXPECT_EQ(run.allocations, 0u);
  EXPECT_GE(run.fresh, kTicks - 1);
  EXPECT_EQ(rig.hub->frames_from_master(1 << 5 | 0x09) - requests1,
            static_cast<std::uint64_t>(kTicks))
      << "axis 1's own request each tick";
  EXPECT_EQ(rig.hub->frames_from_master(2 << 5 | 0x09) - requests2,
            static_cast<std::uint64_t>(kTicks));
  EXPECT_NEAR(rig.hub->drive(0).applied_force(), -1.0, 1e-6);
  EXPECT_NEAR(rig.hub->drive(1).applied_force(), 2.0, 1e-6);
  EXPECT_LT(s[0].position, 0.0);
  EXPECT_GT(s[1].position, 0.0);
  ASSERT_TRUE(rig.hub->drive(1).inject(PeerFault::kDeviceFault));
  EXPECT_EQ(run_until_fault(rig, 500), IoStatus::kDeviceFault);
  rig.tick(forces, s);
  EXPECT_EQ(rig.hub->drive(0).applied_force(), 0.0) << "the healthy axis's torque too";
  const std::string why = rig.device->describe_fault();
  EXPECT_TRUE(has(why, "odrive node 2")) << why;
  rig.device->disable();
  EXPECT_FALSE(rig.hub->drive(0).output_on());
  EXPECT_FALSE(rig.hub->drive(1).output_on());
}

// `hapticd run --loopback` of several nodes: the driver's loopback is the bus of one simulated
// drive per node, moving one gantry.
TEST(CanNodesLoopback, TheLoopbackOfSeveralNodesIsOneDrivePerNodeMovingOneMechanism) {
  wiring::Loopback pair = wiring::find_driver("can").make_loopback(gantry());
  ASSERT_NE(pair.peer->joint_plant(), nullptr);
  EXPECT_EQ(pair.peer->joint_plant()->joints(), 2);
  const auto& bus = dynamic_cast<const sim::CanBusPeer&>(*pair.peer);
  EXPECT_EQ(bus.nodes(), 2u);
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
