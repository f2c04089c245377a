// The loop at several joints (docs/kinematics.md): the simulated delta of config/sim-delta.yaml
// inside a box of six walls, a task-space hand pushing into a face, an edge and a corner; it
// comes to rest at F/K along each normal. And what the loop owes every device: no allocation a
// tick, zero torque on every joint after a fault, a pose fault named.
#include <fcntl.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>

#include "alloc_counter.h"
#include "client/state_reader.h"
#include "config/config_loader.h"
#include "control/scene.h"
#include "freerun.h"
#include "loop/servo_loop.h"
#include "scene_rig.h"
#include "sim/sim_device.h"
#include "telemetry/state_block.h"

namespace hapticd::loop {
namespace {

using kinematics::Vec3;

// At rest after the press has held (t = 2 s): along each wall the hand pushes into, the depth
// is the hand's force along its normal over K, within 2 %.
void expect_rest_at_f_over_k(const std::string& direction, int walls_pushed) {
  SceneRig rig(delta_config("direction: [1, 1, -1]", "direction: " + direction));
  ServoLoop loop(rig.device, rig.controller, nullptr, rig.options(2000));
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  ASSERT_EQ(r.fault.cause, FaultCause::kNone) << describe(r.fault);
  const sim::JointPlant& plant = *rig.device.joint_plant();
  const Vec3 x = plant.task_position();
  const Vec3 f = plant.hand_force();
  int pushed = 0;
  for (std::size_t i = 0; i < rig.cfg.walls.size(); ++i) {
    const config::TaskWallConfig& w = rig.cfg.walls[i];
    const double along = f.dot(w.normal);
    if (along <= 0.1) continue;  // the hand does not push into this one
    ++pushed;
    const double depth = w.normal.dot(x - w.point);
    EXPECT_NEAR(depth, along / w.law.stiffness, 0.02 * along / w.law.stiffness)
        << "wall " << i << " pressed along " << direction;
  }
  EXPECT_EQ(pushed, walls_pushed) << "hand force " << f.transpose();
  EXPECT_GT(r.count(kCounterContactTicks), 500u);
  EXPECT_EQ(r.count(kCounterSaturatedTicks), 0u);
}

TEST(SceneLoop, DeltaPressedIntoAFaceRestsAtForceOverStiffness) {
  expect_rest_at_f_over_k("[1, 0, 0]", 1);
}

TEST(SceneLoop, DeltaPressedIntoAnEdgeRestsAtForceOverStiffnessAlongBothNormals) {
  expect_rest_at_f_over_k("[1, 1, 0]", 2);
}

TEST(SceneLoop, DeltaPressedIntoACornerRestsAtForceOverStiffnessAlongAllThreeNormals) {
  expect_rest_at_f_over_k("[1, 1, -1]", 3);
}

// With every tick published to the clients' state block too.
TEST(SceneLoop, NoHeapAllocationPerTick) {
  SceneRig rig(delta_config());
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  telemetry::StateBlock block(4096, rig.cfg.loop.period_ns(), 3, 3);
  LoopOptions o = rig.options(3000);
  o.state = &block;
  ServoLoop loop(rig.device, rig.controller, &ring, o);
  const std::atomic<bool> stop{false};
  hapticd::testing::AllocationScope scope;
  const LoopResult r = loop.run(stop);
  EXPECT_EQ(scope.count(), 0u) << "allocations on the RT path over " << r.ticks << " ticks";
  EXPECT_EQ(r.fault.cause, FaultCause::kNone);
  EXPECT_GT(r.count(kCounterContactTicks), 100u);
  EXPECT_EQ(block.published(), 3000u);
}

// What the clients read each tick is what the tick did: the task position and the force that
// acted through the walls, each joint's torque, the contact bits; velocities by difference.
TEST(SceneLoop, TheStateBlockSaysWhatEachTickDid) {
  SceneRig rig(delta_config("direction: [1, 1, -1]", "direction: [1, 0, 0]"));
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  telemetry::StateBlock block(4096, rig.cfg.loop.period_ns(), 3, 3);
  LoopOptions o = rig.options(2000);
  o.state = &block;
  ServoLoop loop(rig.device, rig.controller, &ring, o);
  const std::atomic<bool> stop{false};
  ASSERT_EQ(loop.run(stop).fault.cause, FaultCause::kNone);
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  client::StateReader reader(fcntl(block.fd(), F_DUPFD_CLOEXEC, 0));
  client::StateSample s, before;
  ASSERT_EQ(reader.read(1998, before), client::StateReader::Read::kOk);
  ASSERT_EQ(reader.read(1999, s), client::StateReader::Read::kOk);
  const telemetry::TickRecord& last = records.back();
  EXPECT_EQ(s.tick, last.tick);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(s.x[i], last.task_position[i]);
  EXPECT_EQ(s.effort[0], last.force_commanded);
  EXPECT_EQ(s.effort[2], last.joint_force[1]);
  EXPECT_EQ(s.wall_contact, last.wall_contact);
  EXPECT_EQ(s.wall_contact, 1u) << "at rest against the +x face alone";
  // At rest: the walls push back on the hand along -x, K times the depth beyond the face.
  const double depth = s.x[0] - 0.02;
  EXPECT_NEAR(s.f[0], -500.0 * depth, 0.02 * 500.0 * depth);
  EXPECT_NEAR(s.f[1], 0.0, 1e-9);
  EXPECT_NEAR(s.v[0], (s.x[0] - before.x[0]) / 1e-3, 1e-9);
}

// A client's move (wall_moves.h) is taken at the next tick boundary without allocating and
// marked in the log: the +x face moved 10 mm out, the delta pressed along +x rests against it
// where it went, at F/K beyond it.
TEST(SceneLoop, AMovedFaceIsTakenAtATickBoundaryWithoutAllocatingAndMarked) {
  SceneRig rig(delta_config("direction: [1, 1, -1]", "direction: [1, 0, 0]"));
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  WallMoves moves;
  LoopOptions o = rig.options(2000);
  o.wall_moves = &moves;
  ServoLoop loop(rig.device, rig.controller, &ring, o);
  moves.loop_starting();
  const std::uint64_t offer = moves.offer(0, Vec3(0.03, 0.0, 0.11));
  EXPECT_EQ(offer, 1u);
  const std::atomic<bool> stop{false};
  LoopResult r;
  {
    hapticd::testing::AllocationScope scope;
    r = loop.run(stop);
    EXPECT_EQ(scope.count(), 0u) << "allocations on the RT path over " << r.ticks << " ticks";
  }
  ASSERT_EQ(r.fault.cause, FaultCause::kNone) << describe(r.fault);
  const std::optional<WallMoves::Taken> taken = moves.await(offer, std::chrono::milliseconds(0));
  ASSERT_TRUE(taken.has_value());
  EXPECT_EQ(taken->tick, 0u);
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  ASSERT_GT(records.size(), 1u);
  EXPECT_EQ(records[0].marker, telemetry::kMarkerWallMoved);
  EXPECT_EQ(records[0].tick, 0u);
  EXPECT_EQ(records[0].deepest_wall, 0);
  EXPECT_EQ(records[0].task_position[0], 0.03);
  EXPECT_EQ(records[1].marker, telemetry::kMarkerNone);
  const sim::JointPlant& plant = *rig.device.joint_plant();
  const double along = plant.hand_force().x();
  EXPECT_NEAR(plant.task_position().x() - 0.03, along / 500.0, 0.02 * along / 500.0);
  // Nothing more was offered: the next run takes nothing and marks nothing.
  EXPECT_EQ(moves.take(99, [](std::size_t, const Vec3&) { FAIL() << "taken twice"; }), 0u);
}

TEST(SceneLoop, RecordsCarryEveryJointAndTheTaskPosition) {
  SceneRig rig(delta_config());
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  ServoLoop loop(rig.device, rig.controller, &ring, rig.options(1500));
  const std::atomic<bool> stop{false};
  loop.run(stop);
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  ASSERT_EQ(records.size(), 1500u);
  std::uint8_t contact = 0;
  for (const telemetry::TickRecord& r : records) contact |= r.wall_contact;
  const telemetry::TickRecord& last = records.back();
  EXPECT_EQ(last.joints, 3);
  const Vec3 q = rig.device.joint_plant()->joint_positions();
  // The record's joints are those read at the start of its tick, the plant's one period on.
  EXPECT_NEAR(last.position, q[0], 1e-3);
  EXPECT_NEAR(last.joint_position[1], q[2], 1e-3);
  EXPECT_NEAR(last.task_position[2], rig.device.joint_plant()->task_position()[2], 1e-3);
  EXPECT_EQ(contact, 0b100101) << "walls +x, +y and -z (0, 2 and 5) were touched";
}

TEST(SceneLoop, ADeviceFaultZeroesEveryJoint) {
  SceneRig rig(delta_config());
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  ServoLoop loop(rig.device, rig.controller, &ring, rig.options(800));
  const std::atomic<bool> stop{false};
  ASSERT_EQ(loop.run(stop).fault.cause, FaultCause::kNone);
  rig.device.inject(sim::PeerFault::kDeviceFault);
  const LoopResult r = loop.run(stop);
  EXPECT_EQ(r.fault.cause, FaultCause::kDeviceReported);
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  ASSERT_GE(records.size(), 3u);
  // The first run's last tick, then the second run's re-armed marker and its faulted tick.
  const telemetry::TickRecord& pushing = records[records.size() - 3];
  ASSERT_EQ(records[records.size() - 2].marker, telemetry::kMarkerRearmed);
  const telemetry::TickRecord& fault = records.back();
  EXPECT_NE(pushing.force_commanded, 0.0);  // the press was pushing on every joint
  EXPECT_NE(pushing.joint_force[0], 0.0);
  EXPECT_NE(pushing.joint_force[1], 0.0);
  ASSERT_TRUE(fault.flags & telemetry::kFlagFault);
  EXPECT_EQ(fault.force_commanded, 0.0);
  EXPECT_EQ(fault.joint_force[0], 0.0);
  EXPECT_EQ(fault.joint_force[1], 0.0);
  for (std::size_t j = 0; j < 3; ++j) EXPECT_EQ(rig.device.last_command(j), 0.0) << "joint " << j;
}

// device.max_force per joint: a weak third motor saturates alone, and the whole torque is
// scaled down with it (the direction the walls push in kept), never past any joint's limit.
TEST(SceneLoop, EachJointSaturatesAtItsOwnLimit) {
  SceneRig rig(delta_config("max_force: 1.0 ", "max_force: [1.0, 1.0, 0.02] "));
  ASSERT_EQ(rig.cfg.device.max_force[2], 0.02);
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  ServoLoop loop(rig.device, rig.controller, &ring, rig.options(2000));
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  EXPECT_GT(r.count(kCounterSaturatedTicks), 0u);
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  double most = 0.0;
  for (const telemetry::TickRecord& t : records) {
    EXPECT_LE(std::abs(t.force_commanded), 1.0);
    EXPECT_LE(std::abs(t.joint_force[0]), 1.0);
    EXPECT_LE(std::abs(t.joint_force[1]), 0.02 * (1.0 + 1e-12)) << "tick " << t.tick;
    most = std::max(most, std::abs(t.joint_force[1]));
  }
  EXPECT_NEAR(most, 0.02, 1e-12) << "the third joint reached its limit";
}

TEST(SceneLoop, LeavingTheWorkspaceIsANamedPoseFaultWithZeroTorque) {
  // No wall below: the hand drags the effector down through the workspace's floor at z = 0.07.
  SceneRig rig(delta_config("direction: [1, 1, -1]", "direction: [0, 0, -1]"));
  rig.cfg.walls.pop_back();
  SceneWalls open(std::make_unique<control::Scene>(control::make_scene(rig.cfg)),
                  std::vector<control::ObserverParams>(5, control::observer_params(rig.cfg, 0)));
  SceneState state(rig.cfg.device.kinematics, open, rig.cfg.device.max_force.per_joint());
  LoopOptions o = freerun(2000);
  o.scene = &state;
  ServoLoop loop(rig.device, rig.controller, nullptr, o);
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  ASSERT_EQ(r.fault.cause, FaultCause::kPose);
  EXPECT_NE(describe(r.fault).find("outside workspace"), std::string::npos) << describe(r.fault);
  for (std::size_t j = 0; j < 3; ++j) EXPECT_EQ(rig.device.last_command(j), 0.0);
}

// A live reload of the walls (SceneSwap): offered from another thread while the loop runs,
// taken at a tick boundary without allocating, every wall going on from its own (armed, its
// observer's energy kept), and the delta pressed into its corner follows the +x face moved
// 10 mm out (its rest point by 10 mm K / (K + k_h): the hand's spring gives way too).
TEST(SceneLoop, NewWallsAreTakenAtATickBoundaryWithoutAllocatingAndTheEffectorFollows) {
  SceneRig rig(delta_config("hold: 1.5", "hold: 200"));
  SceneSwap swap;
  LoopOptions o = rig.options(1'000'000);  // until the offering thread has seen enough
  o.scene_swap = &swap;
  ServoLoop loop(rig.device, rig.controller, nullptr, o);
  config::Config moved = rig.cfg;
  moved.walls[0].point[0] = 0.03;
  auto next = std::make_unique<SceneWalls>(
      std::make_unique<control::Scene>(control::make_scene(moved)),
      std::vector<control::ObserverParams>(moved.walls.size(), control::observer_params(moved, 0)));
  for (std::size_t i = 0; i < moved.walls.size(); ++i) next->continues[i] = static_cast<int>(i);

  std::atomic<bool> stop{false};
  double x0 = 0.0, energy = 0.0;
  const auto contact = [&] { return loop.counters()[kCounterContactTicks].value(); };
  const auto wait_for = [&](auto done) {
    while (!done()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  };
  swap.loop_starting();
  std::thread client([&] {
    wait_for([&] { return contact() > 1000; });  // pressed into the corner, at rest
    x0 = loop.live().task_position[0].load();
    energy = loop.live().observer_energy_j.load();
    swap.offer(next.get());
    wait_for([&] { return swap.swaps() == 1; });
    const std::uint64_t swapped = contact();
    wait_for([&] { return contact() > swapped + 2000; });  // 2 s on: at rest again
    stop = true;
  });
  LoopResult r;
  {
    hapticd::testing::AllocationScope scope;
    r = loop.run(stop);
    EXPECT_EQ(scope.count(), 0u) << "the swap and the ticks around it allocate nothing";
  }
  client.join();
  ASSERT_EQ(r.fault.cause, FaultCause::kNone) << describe(r.fault);
  ASSERT_GT(x0, 0.02) << "pressed beyond the +x face";
  EXPECT_EQ(swap.swaps(), 1u);
  EXPECT_EQ(swap.retire(), &rig.walls) << "the replaced walls come back to be destroyed";
  EXPECT_EQ(rig.state.walls, next.get());
  EXPECT_EQ(r.count(kCounterReloads), 1u);
  EXPECT_EQ(r.count(kCounterUnarmedTicks), 0u) << "every wall went on armed";
  const double k = rig.cfg.walls[0].law.stiffness, kh = rig.cfg.device.sim.op.stiffness;
  EXPECT_NEAR(rig.device.joint_plant()->task_position()[0], x0 + 0.01 * k / (k + kh), 2e-4);
  // The face moving into the hand did work on it, which the wall's observer counts: less
  // energy than before the move, and still above zero (passive overall).
  EXPECT_LT(next->totals().energy_j, energy);
  EXPECT_GT(next->totals().energy_j, 0.0);
}

// What a swap carries over (SceneWalls::continue_from): each continued wall's observer its
// energies exactly, a removed wall's into `ended` (the run's totals keep it), a new wall
// nothing.
TEST(SceneLoop, ASwapCarriesEachObserverOnAndKeepsWhatRemovedWallsObserved) {
  const config::Config cfg = delta_config();
  const auto walls_of = [&](std::size_t n) {
    config::Config c = cfg;
    c.walls.resize(n);
    return std::make_unique<SceneWalls>(
        std::make_unique<control::Scene>(control::make_scene(c)),
        std::vector<control::ObserverParams>(n, control::observer_params(c, 0)));
  };
  auto running = walls_of(3);
  for (std::size_t i = 0; i < 3; ++i) {  // each wall's coordinate pushed in and out again
    control::PassivityObserver& o = running->observers[i];
    for (int k = 0; k < 50; ++k) {
      o.observe(1e-3 * (i + 1) * std::sin(0.2 * k), true, 1);
      o.commanded(-0.5 * (i + 1) * std::sin(0.2 * k), 0.0);
    }
  }
  const SceneWalls::Totals before = running->totals();
  auto next = walls_of(3);
  next->continues = {2, 0, -1};  // wall 1 removed, wall 2 moved first, a new one last
  next->continue_from(*running);
  EXPECT_EQ(next->observers[0].energy_j(), running->observers[2].energy_j());
  EXPECT_EQ(next->observers[1].wall_work_j(), running->observers[0].wall_work_j());
  EXPECT_EQ(next->observers[2].energy_j(), 0.0);
  EXPECT_EQ(next->ended.energy_j, running->observers[1].energy_j());
  EXPECT_NEAR(next->totals().energy_j, before.energy_j, 1e-15);
  EXPECT_NEAR(next->totals().wall_work_j, before.wall_work_j, 1e-15);
}

}  // namespace
}  // namespace hapticd::loop
