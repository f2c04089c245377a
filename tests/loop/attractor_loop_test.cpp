// An attractor in the loop (docs/kinematics.md, attractors): the simulated delta of
// config/sim-delta.yaml with its box replaced by one attractor, pressed by the hand. What a user
// would feel if it broke: the device at rest anywhere but where the attractor's pull balances the
// hand (K (x - p) = F, in all three directions at once), or a fault from the runaway guard while
// the attractor pulls, as it is meant to, from afar.
#include <gtest/gtest.h>

#include <atomic>

#include "scene_rig.h"

namespace hapticd::loop {
namespace {

using kinematics::Vec3;

// The box's six walls replaced by `attractor` (a flow mapping's keys).
config::Config with_attractor(const std::string& attractor) {
  std::string yaml = delta_yaml();
  const auto walls = yaml.find("\nwalls:");
  const auto end = yaml.find("\nsafety:", walls);
  EXPECT_NE(walls, std::string::npos);
  EXPECT_NE(end, std::string::npos);
  yaml.replace(walls, end - walls, "\nwalls:\n  - {kind: attractor, " + attractor + "}\n");
  return config::load_config_text(yaml, "sim-delta-attractor.yaml");
}

TEST(AttractorLoop, DeltaPressedByTheHandRestsWhereThePullBalancesTheHandInEveryDirection) {
  SceneRig rig(with_attractor("point: [0.005, -0.004, 0.115], stiffness: 400, damping: 0.05"));
  ServoLoop loop(rig.device, rig.controller, nullptr, rig.options(2000));
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  ASSERT_EQ(r.fault.cause, FaultCause::kNone) << describe(r.fault);
  const sim::JointPlant& plant = *rig.device.joint_plant();
  const Vec3 x = plant.task_position();
  const Vec3 f = plant.hand_force();
  const Vec3 pull = 400.0 * (x - Vec3(0.005, -0.004, 0.115));
  ASSERT_GT(f.norm(), 1.0) << "the hand presses";
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(pull[a], f[a], 0.02 * f.norm()) << "axis " << a << ", x " << x.transpose();
  }
  EXPECT_EQ(r.count(kCounterSaturatedTicks), 0u);
}

// The hand drags the device 60 mm away from an attractor whose max_force is less than the
// hand's: the attractor pulls at its max_force, saturated, the whole time, and that is no
// runaway: an attractor is not a wall the device went through.
TEST(AttractorLoop, AnAttractorPullingAtItsMaxForceFromAfarIsNoRunaway) {
  SceneRig rig(with_attractor("point: [0, 0, 0.11], stiffness: 400, damping: 0.05, max_force: 2"));
  ServoLoop loop(rig.device, rig.controller, nullptr, rig.options(2000));
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  ASSERT_EQ(r.fault.cause, FaultCause::kNone) << describe(r.fault);
  const sim::JointPlant& plant = *rig.device.joint_plant();
  const Vec3 away = plant.task_position() - Vec3(0, 0, 0.11);
  EXPECT_GT(away.norm(), 0.02) << "the hand held it away";
  EXPECT_GT(r.count(kCounterSaturatedTicks), 500u);
  EXPECT_NEAR(plant.hand_force().norm(), 2.0, 0.1) << "the hand balances the attractor's 2 N";
}

}  // namespace
}  // namespace hapticd::loop
