// The servo loop of several CAN nodes against the simulated bus `hapticd run --loopback` plays
// (sim/peers/can/can_bus_peer.h): the drives of config/can-gantry.yaml move one simulated
// gantry, and its hand, pressed along the diagonal, comes to rest at F/K along the wall's
// normal and goes as deep as the sim driver's gantry with the same total delay does.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "can_nodes_bus.h"
#include "control/controller.h"
#include "control/scene.h"
#include "loop/scene_tick.h"
#include "loop/servo_loop.h"
#include "scene_run.h"
#include "sim/peers/paced_device.h"
#include "wiring/registry.h"

namespace hapticd::drivers::can::testing {
namespace {

using kinematics::Vec3;

// `ticks` ticks of cfg's scene on `device` in freerun, recorded into `ring` (or not).
loop::LoopResult run_scene(const config::Config& cfg, Device& device, std::uint64_t ticks,
                           telemetry::SpscRing<telemetry::TickRecord>* ring) {
  device.configure();
  device.enable();
  const loop::LoopResult r = hapticd::testing::run_scene_loop(cfg, device, ticks, ring);
  device.close();
  return r;
}

TEST(CanNodesLoopback, TheGantrysHandRestsAtForceOverStiffnessAlongTheDiagonal) {
  NodesRig rig(load_example("can-gantry.yaml"));
  sim::PacedDevice device(std::move(rig.device), *rig.runner);
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  const loop::LoopResult can = run_scene(rig.cfg, device, 2000, &ring);
  ASSERT_EQ(can.fault.cause, loop::FaultCause::kNone) << loop::describe(can.fault);
  EXPECT_LE(can.count(loop::kCounterStaleTicks), 1u) << "only the first tick, before any SYNC";
  EXPECT_GT(can.count(loop::kCounterContactTicks), 1000u);

  // The press holds from 0.7 s to 2.2 s. At rest the hand's spring and the wall share the
  // set-point's reach past the face: K p = k_h (depth - n . (point - origin) - p). The drives'
  // encoders (10 um counts) leave it dithering by a count: its mean over the last 0.5 s.
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  ASSERT_EQ(records.size(), 2000u);
  double rest = 0.0;
  for (std::size_t k = 1500; k < 2000; ++k) rest += records[k].penetration / 500.0;
  const config::TaskWallConfig& wall = rig.cfg.walls.front();
  const config::OperatorSpec& hand = rig.cfg.device.sim.op;
  const double reach = 0.05 - wall.normal.dot(wall.point - hand.origin);
  const double expected = hand.stiffness * reach / (wall.law.stiffness + hand.stiffness);
  EXPECT_NEAR(rest, expected, 0.02 * expected) << "F/K along the diagonal";
  const Vec3 q = rig.hub->joint_plant()->joint_positions();
  EXPECT_NEAR(q[0], q[1], 2e-5) << "a diagonal press moves both joints alike";
  EXPECT_GT(q[0], 0.02) << "both drives moved the one gantry past the wall's point";

  // The sim driver on the same file, with the CAN driver's one sample of delay on the wall.
  const config::Config sim_cfg = load_example(
      "can-gantry.yaml", {"device.driver=sim", "device.can=null", "walls[0].delay_samples=1"});
  wiring::Loopback sim = wiring::find_driver("sim").make_loopback(sim_cfg);
  const loop::LoopResult reference = run_scene(sim_cfg, *sim.device, 2000, nullptr);
  ASSERT_EQ(reference.fault.cause, loop::FaultCause::kNone) << loop::describe(reference.fault);
  EXPECT_NEAR(can.max_penetration, reference.max_penetration, 0.05 * reference.max_penetration)
      << "can " << can.max_penetration * 1e3 << " mm, sim " << reference.max_penetration * 1e3
      << " mm";
  RecordProperty("rest_mm", std::to_string(rest * 1e3));
  RecordProperty("penetration_can_mm", std::to_string(can.max_penetration * 1e3));
  RecordProperty("penetration_sim_mm", std::to_string(reference.max_penetration * 1e3));
}

}  // namespace
}  // namespace hapticd::drivers::can::testing
