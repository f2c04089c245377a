// Attractors (control/scene.h): a spring-damper to a point, its law along each task axis. What a
// user would feel if it broke: a pull that is not towards the point, one stiffer along some axis
// than another, damping only along the axes it is displaced on, a yank from afar beyond its
// max_force or in another direction, a yank or a kick when one appears, a move that jumps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/scene.h"
#include "kinematics/kinematics.h"

namespace hapticd::control {
namespace {

using kinematics::Vec3;

const Vec3 kNoJointLimit = Vec3::Constant(1e9);

// A unit cartesian device of three joints with `walls` (YAML flow entries).
config::Config attractor_scene_config(const std::string& walls) {
  return config::load_config_text(
      "device:\n  max_force: 100\n  kinematics: {kind: cartesian, "
      "joints: 3}\nwalls:\n" +
          walls,
      "attractor.yaml");
}

SceneStep step_at(Scene& scene, const config::Config& cfg, const Vec3& x, int ticks = 1) {
  SceneStep s;
  for (int i = 0; i < ticks; ++i) {
    s = scene.step(kinematics::forward(cfg.device.kinematics, x, x), kNoJointLimit);
  }
  return s;
}

// Ticks enough for a new attractor to slide from the device to its point (0.25 mm a tick at
// safety.max_wall_speed's default): 100 ticks, 25 mm.
constexpr int kArrived = 100;

TEST(Attractor, PullsTowardsItsPointWithKTimesTheDisplacementInEveryDirection) {
  const config::Config cfg = attractor_scene_config(
      "  - {kind: attractor, point: [0.01, -0.02, 0.03], "
      "stiffness: 400, damping: 0}\n");
  const Vec3 p(0.01, -0.02, 0.03);
  for (const Vec3& d : {Vec3(0.002, 0, 0), Vec3(0, -0.003, 0), Vec3(0.001, 0.002, -0.004),
                        Vec3(-0.005, 0.005, 0.005)}) {
    Scene scene = make_scene(cfg);
    ASSERT_EQ(scene.channels(), 3u);
    const SceneStep s = step_at(scene, cfg, p + d, kArrived);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(s.force[a], -400.0 * d[a], 1e-12) << d.transpose();
    EXPECT_EQ(s.contact, 1u) << "an attractor always acts";
    EXPECT_FALSE(s.flags & kControlUnarmed);
  }
}

// A new attractor starts where the device is and slides to its point at safety.max_wall_speed:
// its pull grows by K max_move a tick, with no damping kick (B d / T would be 40 N here).
TEST(Attractor, ANewAttractorStartsAtTheDeviceAndSlidesToItsPoint) {
  const config::Config cfg = attractor_scene_config(
      "  - {kind: attractor, point: [0, 0, 0], stiffness: 400, damping: 4}\n");
  Scene scene = make_scene(cfg);
  const Vec3 x(0.01, 0.0, 0.0);
  const double step = cfg.safety.max_wall_speed * cfg.loop.sample_period_s();
  double last = 0.0;
  for (int k = 1; k <= 45; ++k) {
    const double pull = -step_at(scene, cfg, x).force.x();
    const double spring = 400.0 * std::min(k * step, 0.01);
    // The damping sees the point move at the wall speed: B max_move / T until it arrives.
    EXPECT_NEAR(pull, spring + (k * step <= 0.01 + 1e-12 ? 4.0 * 0.25 : 0.0), 1e-9) << k;
    EXPECT_LE(pull, 5.0 + 1e-9);
    last = pull;
  }
  EXPECT_NEAR(last, 4.0, 1e-9);
  // After a reset (a cleared fault), it starts afresh from the device again.
  scene.reset();
  EXPECT_NEAR(step_at(scene, cfg, Vec3(-0.02, 0, 0)).force.x(), 400.0 * step + 1.0, 1e-9);
}

// Its damping is B v for the whole velocity, not only along the way it is displaced: a device
// moving around the point at its distance is slowed as much as one moving towards it.
TEST(Attractor, DampsTheWholeVelocityBesideTheSpring) {
  const config::Config cfg = attractor_scene_config(
      "  - {kind: attractor, point: [0, 0, 0], stiffness: 100, damping: 3, "
      "discretization: backward}\n");
  Scene scene = make_scene(cfg);
  const Vec3 x0(0.01, 0.0, 0.0), v(0.0, 0.2, -0.1);  // m/s, across the displacement
  step_at(scene, cfg, x0, kArrived);
  const double t = cfg.loop.sample_period_s();
  const SceneStep s = step_at(scene, cfg, x0 + v * t);
  const Vec3 expected = -100.0 * (x0 + v * t) - 3.0 * v;
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(s.force[a], expected[a], 1e-9) << a;
}

// From afar its force is its max_force exactly, still pointing at the point: the three axes are
// scaled together, never each clipped alone (which would turn the pull).
TEST(Attractor, FromAfarPullsAtItsMaxForceStraightAtThePoint) {
  const config::Config cfg = attractor_scene_config(
      "  - {kind: attractor, point: [0, 0, 0], stiffness: 1000, damping: 0, max_force: 2}\n");
  Scene scene = make_scene(cfg);
  const Vec3 x(0.05, -0.02, 0.01);
  const SceneStep s = step_at(scene, cfg, x, 2 * kArrived);
  EXPECT_NEAR(s.force.norm(), 2.0, 1e-12);
  EXPECT_NEAR(s.force.normalized().dot(-x.normalized()), 1.0, 1e-12);
  EXPECT_TRUE(s.flags & kControlSaturated);
  // Near, within its limit: the spring's own force, not saturated.
  Scene near = make_scene(cfg);
  const SceneStep n = step_at(near, cfg, Vec3(0.001, 0, 0), kArrived);
  EXPECT_NEAR(n.force.x(), -1.0, 1e-12);
  EXPECT_FALSE(n.flags & kControlSaturated);
}

// Beside walls: each wall's contact bit as before, the attractor's always set; the forces add.
TEST(Attractor, AddsToTheWallsAndKeepsTheirContactBits) {
  const config::Config cfg = attractor_scene_config(
      "  - {point: [0.02, 0, 0], normal: [1, 0, 0], stiffness: 500}\n"
      "  - {kind: attractor, point: [0, 0, 0], stiffness: 100, damping: 0}\n");
  Scene scene = make_scene(cfg);
  ASSERT_EQ(scene.size(), 2u);
  ASSERT_EQ(scene.channels(), 4u);
  EXPECT_EQ(scene.wall_of(3), 1u);
  EXPECT_EQ(scene.direction(3), Vec3::UnitZ());
  const SceneStep outside = step_at(scene, cfg, Vec3(0.01, 0, 0), kArrived);
  EXPECT_EQ(outside.contact, 2u);
  EXPECT_NEAR(outside.force.x(), -1.0, 1e-12);
  const SceneStep inside = step_at(scene, cfg, Vec3(0.023, 0, 0), 3);
  EXPECT_EQ(inside.contact, 3u);
  EXPECT_NEAR(inside.force.x(), -500.0 * 0.003 - 100.0 * 0.023, 1e-9);
}

// A client's move slides the attractor's point at most max_move a tick, as a wall's: the pull
// on a device held still grows by K max_move a tick, never a step.
TEST(Attractor, AMovedAttractorSlidesAtMostMaxMoveATick) {
  const config::Config cfg = attractor_scene_config(
      "  - {kind: attractor, point: [0, 0, 0], stiffness: 1000, damping: 0}\n");
  const control::ControlLaw law = task_wall_law(cfg, cfg.walls[0]);
  Scene scene(std::vector<WallGeometry>{{Vec3::Zero(), Vec3::Zero(), 3}},
              std::vector<ControlLaw>{law}, 0.001);
  EXPECT_NEAR(step_at(scene, cfg, Vec3::Zero(), 3).force.norm(), 0.0, 1e-15);
  scene.move_to(0, Vec3(0.0025, 0.0, 0.0));
  for (const double pull : {1.0, 2.0, 2.5, 2.5}) {
    EXPECT_NEAR(step_at(scene, cfg, Vec3::Zero()).force.x(), pull, 1e-9);
  }
}

TEST(Attractor, NoHeapAllocationPerTick) {
  const config::Config cfg = attractor_scene_config(
      "  - {point: [0.02, 0, 0], normal: [1, 0, 0], stiffness: 500}\n"
      "  - {kind: attractor, point: [0, 0, 0], stiffness: 100, damping: 1, max_force: 1}\n");
  Scene scene = make_scene(cfg);
  step_at(scene, cfg, Vec3::Zero());
  hapticd::testing::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) step_at(scene, cfg, Vec3(0.03 * std::sin(0.01 * i), 0.01, 0));
  EXPECT_EQ(scope.count(), 0u);
}

TEST(Attractor, TheSceneRefusesAttractorsItCannotRun) {
  const ControlLaw law = task_wall_law(attractor_scene_config(""), config::TaskWallConfig{});
  const auto build = [&](WallGeometry g) {
    Scene(std::vector<WallGeometry>{g}, std::vector<ControlLaw>{law});
  };
  EXPECT_THROW(build({Vec3::Zero(), Vec3::Zero(), 4}), std::invalid_argument);
  EXPECT_THROW(build({Vec3::Zero(), Vec3::Zero(), 2, 0.0}), std::invalid_argument);
  EXPECT_NO_THROW(build({Vec3::Zero(), Vec3::Zero(), 2, 1.0}));
}

}  // namespace
}  // namespace hapticd::control
