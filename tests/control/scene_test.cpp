// Walls in task space (control/scene.h): each wall's law along its normal, the sum through J^T,
// one saturation factor for every joint. What a user would feel if it broke: a wall that pulls,
// a corner that pushes along one face only, a diagonal wall whose force turns as it saturates,
// a force through a mechanism that has lost its pose.
#include "control/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "kinematics/kinematics.h"

namespace hapticd::control {
namespace {

using kinematics::Vec3;

ControlLaw wall_law(double k, double b = 0.0, double max_force = 1e9) {
  config::Config c;
  c.loop.rate_hz = 1000.0;
  c.wall.stiffness = k;
  c.wall.damping = b;
  c.device.max_force = max_force;
  ControlLaw l = make_control_law(c);
  l.require_outside_start = false;  // these tests place the device in contact at once
  return l;
}

kinematics::Kinematics cartesian_of(int n, Vec3 scale = Vec3::Ones(), Vec3 sign = Vec3::Ones()) {
  kinematics::Kinematics k;
  k.kind = kinematics::Kind::kCartesian;
  k.cartesian.n = n;
  k.cartesian.scale = scale;
  k.cartesian.sign = sign;
  return k;
}

const Vec3 kUnlimited = Vec3::Constant(1e9);

// Steps the scene `ticks` times at joint position q; returns the last step.
SceneStep hold_at(Scene& scene, const kinematics::Kinematics& k, const Vec3& q, int ticks = 5,
                  const Vec3& limit = kUnlimited) {
  SceneStep s;
  for (int i = 0; i < ticks; ++i) s = scene.step(kinematics::forward(k, q, Vec3::Zero()), limit);
  return s;
}

TEST(Scene, ADiagonalWallPushesAlongItsNormalOutOfTheWall) {
  const Vec3 n = Vec3(1.0, 1.0, 0.0).normalized();
  const std::vector<WallGeometry> g{{Vec3::Zero(), n}};
  const std::vector<ControlLaw> l{wall_law(1000.0, 2.0)};
  Scene scene(g, l);
  // 2 mm into the wall along n, 5 mm along the face: at rest the force is K d, along -n.
  const Vec3 x = 0.002 * n + 0.005 * Vec3(-n.y(), n.x(), 0.0);
  const SceneStep s = hold_at(scene, cartesian_of(2), x);
  EXPECT_NEAR(s.force.x(), -2.0 * n.x(), 1e-12);
  EXPECT_NEAR(s.force.y(), -2.0 * n.y(), 1e-12);
  EXPECT_NEAR(s.tau.x(), s.force.x(), 1e-12);  // a unit gantry: tau = F
  EXPECT_TRUE(s.flags & kControlContact);
}

// Each wall keeps the one-joint law's unilateral contact (docs/math.md): the filters act on
// xi = max(p, 0), so on the tick the device leaves, the damping term sees xi fall and pulls
// once, as the papers' model does; with no_pull that tick gives zero instead. Outside, nothing.
TEST(Scene, LeavingAWallPullsOnlyWhatTheContactLawDoesAndNoPullNotEvenThat) {
  const std::vector<WallGeometry> g{{Vec3(0.01, 0.0, 0.0), Vec3(1.0, 0.0, 0.0)}};
  for (const bool no_pull : {false, true}) {
    ControlLaw l = wall_law(1000.0, 5.0);
    l.no_pull = no_pull;
    const std::vector<ControlLaw> laws{l};
    Scene scene(g, laws);
    hold_at(scene, cartesian_of(1), Vec3(0.012, 0, 0), 3);
    const SceneStep exit = hold_at(scene, cartesian_of(1), Vec3(0.005, 0, 0), 1);
    // f = K 0 + B (0 - 0.002) / T = -10 N: towards the wall (+x) unless no_pull.
    EXPECT_NEAR(exit.force.x(), no_pull ? 0.0 : 10.0, 1e-9) << no_pull;
    const SceneStep after = hold_at(scene, cartesian_of(1), Vec3(0.005, 0, 0), 1);
    EXPECT_EQ(after.force.x(), 0.0) << no_pull;
    EXPECT_FALSE(after.flags & kControlContact);
  }
}

TEST(Scene, ACornerPushesAlongBothFacesAtOnce) {
  // Two faces of a box, x <= 0.02 and y <= 0.01 (normals into the walls: +x, +y).
  const std::vector<WallGeometry> g{{Vec3(0.02, 0, 0), Vec3::UnitX()},
                                    {Vec3(0, 0.01, 0), Vec3::UnitY()}};
  const std::vector<ControlLaw> l{wall_law(1000.0), wall_law(500.0)};
  Scene scene(g, l);
  const SceneStep s = hold_at(scene, cartesian_of(2), Vec3(0.023, 0.014, 0.0));
  EXPECT_NEAR(s.force.x(), -1000.0 * 0.003, 1e-12);
  EXPECT_NEAR(s.force.y(), -500.0 * 0.004, 1e-12);
  EXPECT_NEAR(s.channels[1].penetration, 0.004, 1e-15);
}

TEST(Scene, JointTorquesAreJTransposedForceThroughTheGantrysScaleAndSign) {
  const std::vector<WallGeometry> g{{Vec3::Zero(), Vec3::UnitY()}};
  const std::vector<ControlLaw> l{wall_law(1000.0)};
  Scene scene(g, l);
  // Joint 1 at -2 units of 0.001 m with sign -1: y = +2 mm, 2 N out of the wall (-y).
  const auto k = cartesian_of(2, Vec3(0.001, 0.001, 1.0), Vec3(1.0, -1.0, 1.0));
  const SceneStep s = hold_at(scene, k, Vec3(0.0, -2.0, 0.0));
  EXPECT_NEAR(s.force.y(), -2.0, 1e-9);
  // tau_1 = J_11 F_y = (-1)(0.001 m/unit)(-2 N) = +0.002 N m per unit: it drives q_1 up, y down.
  EXPECT_NEAR(s.tau.y(), 0.002, 1e-12);
  EXPECT_EQ(s.tau.x(), 0.0);
}

TEST(Scene, SaturationScalesEveryJointByOneFactorSoTheForceKeepsItsDirection) {
  const Vec3 n = Vec3(2.0, 1.0, 0.0).normalized();
  const std::vector<WallGeometry> g{{Vec3::Zero(), n}};
  const std::vector<ControlLaw> l{wall_law(1000.0)};
  Scene scene(g, l);
  const SceneStep free = hold_at(scene, cartesian_of(2), 0.01 * n);  // 10 N along -n
  Scene limited(g, l);
  const SceneStep s = hold_at(limited, cartesian_of(2), 0.01 * n, 5, Vec3(2.0, 2.0, 2.0));
  EXPECT_EQ(s.saturation, kinematics::SaturationStatus::kSaturated);
  EXPECT_TRUE(s.flags & kControlSaturated);
  EXPECT_NEAR(std::abs(s.tau.x()), 2.0, 1e-12);  // the larger joint lands on its limit
  EXPECT_NEAR(s.tau.y() / s.tau.x(), free.tau.y() / free.tau.x(), 1e-12);  // same direction
}

TEST(Scene, APoseThatIsNotOkGivesZeroTorque) {
  const std::vector<WallGeometry> g{{Vec3(0, 0, 0.11), Vec3::UnitZ()}};
  const std::vector<ControlLaw> l{wall_law(1000.0)};
  Scene scene(g, l);
  kinematics::Kinematics delta;
  delta.kind = kinematics::Kind::kDelta;
  kinematics::Pose p = kinematics::forward(
      delta, Vec3(0.3, 0.3, 0.3), Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  p.status = kinematics::Status::kNearSingularity;
  const SceneStep s = scene.step(p, kUnlimited);
  EXPECT_FALSE(s.pose_ok);
  EXPECT_EQ(s.tau, Vec3::Zero());
}

TEST(Scene, ANonFiniteLimitIsNamedForTheLoopToFaultOn) {
  const std::vector<WallGeometry> g{{Vec3::Zero(), Vec3::UnitX()}};
  const std::vector<ControlLaw> l{wall_law(1000.0)};
  Scene scene(g, l);
  const SceneStep s = hold_at(scene, cartesian_of(1), Vec3(0.001, 0, 0), 3,
                              Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_TRUE(s.flags & kControlNonFinite);
  EXPECT_EQ(s.tau, Vec3::Zero());
}

TEST(Scene, WhatCannotBeAWallIsRefusedBeforeTheFirstTick) {
  const std::vector<ControlLaw> one{wall_law(1000.0)};
  const std::vector<WallGeometry> not_unit{{Vec3::Zero(), Vec3(1.0, 1.0, 0.0)}};
  EXPECT_THROW(Scene(not_unit, one), std::invalid_argument);
  const std::vector<WallGeometry> two{{Vec3::Zero(), Vec3::UnitX()}, {Vec3::Zero(), Vec3::UnitY()}};
  EXPECT_THROW(Scene(two, one), std::invalid_argument);
  const std::vector<WallGeometry> many(kMaxWalls + 1, {Vec3::Zero(), Vec3::UnitX()});
  const std::vector<ControlLaw> laws(kMaxWalls + 1, wall_law(1000.0));
  EXPECT_THROW(Scene(many, laws), std::invalid_argument);
}

// A client's move (Scene::move_to): the wall slides to its new place at most max_move a tick,
// its law going on; a move past the walls is ignored.
TEST(Scene, AMovedWallSlidesToItsPlaceAtMostMaxMoveATick) {
  const std::vector<WallGeometry> one{{Vec3::Zero(), Vec3::UnitX()}};
  const std::vector<ControlLaw> laws{wall_law(1000.0)};
  Scene scene(one, laws, 0.001);
  const kinematics::Pose at = kinematics::forward(cartesian_of(3), Vec3::Zero(), Vec3::Zero());
  scene.move_to(0, Vec3(-0.0035, 0.0, 0.0));
  scene.move_to(5, Vec3(1.0, 0.0, 0.0));  // no wall 5: nothing
  const double expected[] = {-0.001, -0.002, -0.003, -0.0035, -0.0035};
  for (const double x : expected) {
    scene.step(at, Vec3::Constant(100.0));
    EXPECT_NEAR(scene.geometry(0).point.x(), x, 1e-15);
  }
  // At x = 0 the wall at -3.5 mm along +x holds the device 3.5 mm deep: 3.5 N out.
  EXPECT_NEAR(scene.step(at, Vec3::Constant(100.0)).force.x(), -3.5, 1e-9);
}

TEST(Scene, ABoxOnADeltaStepsWithoutAllocating) {
  std::vector<WallGeometry> box;
  for (int a = 0; a < 3; ++a) {
    Vec3 n = Vec3::Zero();
    n[a] = 1.0;
    box.push_back({Vec3(0, 0, 0.11) + 0.03 * n, n});
    box.push_back({Vec3(0, 0, 0.11) - 0.03 * n, -n});
  }
  const std::vector<ControlLaw> laws(6, wall_law(1000.0, 1.0));
  Scene scene(box, laws);
  kinematics::Kinematics delta;
  delta.kind = kinematics::Kind::kDelta;
  const kinematics::JointSolution q = kinematics::inverse(delta, Vec3(0.031, 0.0, 0.11));
  ASSERT_EQ(q.status, kinematics::Status::kOk);
  Vec3 guess = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  testing::AllocationScope scope;
  SceneStep s;
  for (int i = 0; i < 2000; ++i) {
    const kinematics::Pose p = kinematics::forward(delta, q.q, guess);
    guess = p.x;
    s = scene.step(p, Vec3::Constant(5.0));
  }
  EXPECT_EQ(scope.count(), 0u);
  // 1 mm into the +x face: 1 N out along -x, through the arms.
  EXPECT_NEAR(s.force.x(), -1.0, 1e-9);
  EXPECT_NEAR(s.force.y(), 0.0, 1e-12);
}

// From the file a user writes to the force at a box's corner: each face its own K, each force
// along its own normal at K times the depth along it.
TEST(Scene, ABoxFromTheConfigurationHoldsACornerAtKTimesTheDepthAlongEachNormal) {
  const config::Config cfg = config::load_config_text(R"(device:
  max_force: 100
  kinematics: {kind: cartesian, joints: 3}
walls:
  - {point: [0.05, 0, 0], normal: [1, 0, 0], stiffness: 1000, damping: 2}
  - {point: [0, 0.05, 0], normal: [0, 1, 0], stiffness: 2000}
  - {point: [0, 0, -0.05], normal: [0, 0, -1], stiffness: 500}
)",
                                                      "box.yaml");
  Scene scene = make_scene(cfg);
  ASSERT_EQ(scene.size(), 3u);
  // Outside first (the walls arm once the device has been outside), then into the corner.
  hold_at(scene, cartesian_of(3), Vec3::Zero(), 2);
  const SceneStep s = hold_at(scene, cartesian_of(3), Vec3(0.052, 0.051, -0.054));
  EXPECT_NEAR(s.force.x(), -1000.0 * 0.002, 1e-9);
  EXPECT_NEAR(s.force.y(), -2000.0 * 0.001, 1e-9);
  EXPECT_NEAR(s.force.z(), +500.0 * 0.004, 1e-9);
  EXPECT_EQ(s.saturation, kinematics::SaturationStatus::kWithin);
}

// A wall a swap moved (a reload, a scene request) slides to its new place at most max_move a
// tick (safety.max_wall_speed T): a device held still feels its penetration grow by that much a
// tick, never a step; a wall that stayed where it was does not move at all; a wall whose normal
// a swap turned starts afresh.
TEST(Scene, AWallMovedByASwapSlidesToItsPlaceAtMostMaxMoveATick) {
  const kinematics::Kinematics k = cartesian_of(2);
  const std::vector<ControlLaw> laws = {wall_law(1000), wall_law(1000)};
  Scene before(
      std::vector<WallGeometry>{{Vec3::Zero(), Vec3(1, 0, 0)}, {Vec3(0, -0.1, 0), Vec3(0, -1, 0)}},
      laws, 0.001);
  const Vec3 q(0.005, 0.0, 0.0);  // 5 mm into the first wall
  EXPECT_NEAR(hold_at(before, k, q).channels[0].penetration, 0.005, 1e-12);
  // The first face 3.5 mm towards -x (deeper in), the second where it was.
  Scene after(std::vector<WallGeometry>{{Vec3(-0.0035, 0, 0), Vec3(1, 0, 0)},
                                        {Vec3(0, -0.1, 0), Vec3(0, -1, 0)}},
              laws, 0.001);
  after.continue_from(before, std::vector<int>{0, 1});
  for (const double expected : {0.006, 0.007, 0.008, 0.0085, 0.0085}) {
    const SceneStep s = hold_at(after, k, q, 1);
    EXPECT_NEAR(s.channels[0].penetration, expected, 1e-12);
    EXPECT_NEAR(s.channels[1].penetration, -0.1, 1e-12);
  }
  EXPECT_EQ(after.geometry(0).point, Vec3(-0.0035, 0, 0)) << "arrived exactly";

  // The second wall's normal flipped: the device, 100 mm outside it, is now 100 mm inside a
  // wall that starts afresh and stays off until the device has left it, never a 100 N step.
  ControlLaw fresh = wall_law(1000);
  fresh.require_outside_start = true;
  Scene flipped(std::vector<WallGeometry>{{Vec3(-0.0035, 0, 0), Vec3(1, 0, 0)},
                                          {Vec3(0, -0.1, 0), Vec3(0, 1, 0)}},
                std::vector<ControlLaw>{wall_law(1000), fresh}, 0.001);
  flipped.continue_from(after, std::vector<int>{0, 1});
  const SceneStep s = hold_at(flipped, k, q, 3);
  EXPECT_NEAR(s.channels[1].penetration, 0.1, 1e-12);
  EXPECT_EQ(s.channels[1].force_commanded, 0.0);
  EXPECT_TRUE(s.channels[1].flags & kControlUnarmed);
  EXPECT_NEAR(s.channels[0].force_commanded, -8.5, 1e-9) << "the first wall went on pushing";
  EXPECT_THROW(Scene(std::vector<WallGeometry>{{Vec3::Zero(), Vec3(1, 0, 0)}},
                     std::vector<ControlLaw>{wall_law(1000)}, 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace hapticd::control
