// The gate for attractors (gate/workspace_gate.h): a spring-damper to a point pulls every way,
// so its b_req stands against the least damping the device has in any direction,
// lambda_min(B_c), anywhere in the workspace, and its axes' laws join the walls' in the matrix
// condition as b_req I. What a user would feel if it broke: an attractor admitted because the
// device is well damped along some axes, which then buzzes along the weakest one; an attractor
// and a wall each passing alone and together unstable.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "analysis/normal_passivity.h"
#include "config/config_loader.h"
#include "gate/workspace_gate.h"
#include "kinematics/kinematics.h"

namespace hapticd::gate {
namespace {

using kinematics::Vec3;

// A gantry of x = 0.5 q0, y = 2 q1 with b = 2 per joint: B_c = diag(8, 0.5).
config::Config gantry_attractor(const std::string& walls) {
  return config::load_config_text(R"(device:
  damping: 2
  kinematics: {kind: cartesian, joints: 2, scale: [0.5, 2]}
walls:
)" + walls,
                                  "attractor.yaml");
}

TEST(AttractorGate, ItsDemandStandsAgainstTheWeakestDirectionNotTheStrongest) {
  const config::Config c = gantry_attractor(
      "  - {kind: attractor, point: [0, 0], stiffness: 2000, damping: 0}\n"
      "  - {point: [0.01, 0], normal: [1, 0], stiffness: 2000, damping: 0}\n");
  const WorkspaceReport r = evaluate_workspace(c, 0);
  ASSERT_EQ(r.walls.size(), 2u);
  EXPECT_NEAR(r.walls[0].worst_damping, 0.5, 1e-12);  // lambda_min(B_c): the y axis
  EXPECT_NEAR(r.walls[1].worst_damping, 8.0, 1e-12);  // the wall along x: b_n
  EXPECT_NEAR(r.walls[0].required_damping, r.walls[1].required_damping, 1e-12) << "the same law";
  EXPECT_FALSE(r.walls[0].passive);  // K T / 2 = 1 > 0.5
  EXPECT_TRUE(r.walls[1].passive);
  EXPECT_FALSE(r.pass);
  ASSERT_FALSE(r.reasons.empty());
  EXPECT_NE(r.reasons[0].find("walls[0] (an attractor): b_req 1 exceeds"), std::string::npos)
      << r.reasons[0];
  EXPECT_NE(r.reasons[0].find("lambda_min(B_c) = 0.5 the least damping the device has in any "
                              "direction"),
            std::string::npos)
      << r.reasons[0];
  // The largest K that passes: K T / 2 <= (1 - margin) 0.5.
  ASSERT_EQ(r.walls[0].max_stiffness.kind, analysis::StiffnessLimit::Kind::kBounded);
  const double keep = 1.0 - c.safety.passivity_margin;
  EXPECT_NEAR(r.walls[0].max_stiffness.value, 2.0 * keep * 0.5 / c.loop.sample_period_s(),
              1e-6 * r.walls[0].max_stiffness.value);
}

// Each passes alone; where the wall acts the attractor acts too, and along y they need
// b_a + b_w of the 0.5 there.
TEST(AttractorGate, AnAttractorAndAWallThatEachPassAloneAreJudgedTogether) {
  const config::Config c = gantry_attractor(
      "  - {kind: attractor, point: [0, 0], stiffness: 500, damping: 0}\n"
      "  - {point: [0, 0.01], normal: [0, 1], stiffness: 500, damping: 0}\n");
  const WorkspaceReport r = evaluate_workspace(c, 0);
  ASSERT_EQ(r.walls.size(), 2u);
  EXPECT_TRUE(r.walls[0].passive);
  EXPECT_TRUE(r.walls[1].passive);
  const double keep = 1.0 - c.safety.passivity_margin;
  const double expected = 0.5 - (r.walls[0].required_damping + r.walls[1].required_damping) / keep;
  ASSERT_LT(expected, 0.0);
  EXPECT_NEAR(r.corner_margin, expected, 1e-12);
  EXPECT_FALSE(r.pass);
  EXPECT_FALSE(r.movable);
  // Alone, the attractor acts everywhere and meets nothing: it passes and may be moved.
  const WorkspaceReport alone = evaluate_workspace(
      gantry_attractor("  - {kind: attractor, point: [0, 0], stiffness: 500, damping: 0}\n"), 0);
  EXPECT_TRUE(alone.pass) << (alone.reasons.empty() ? "" : alone.reasons[0]);
  EXPECT_TRUE(alone.movable) << alone.not_movable;
}

// Its point where the device cannot go: it would press the device into the mechanism's limits.
TEST(AttractorGate, AnAttractorWhosePointIsOutsideTheWorkspaceIsRefused) {
  const config::Config c = config::load_config_text(
      "device:\n  damping: 0.05\n  kinematics: {kind: delta}\nwalls:\n"
      "  - {kind: attractor, point: [0, 0, 0.3], stiffness: 10, damping: 0}\n",
      "attractor.yaml");
  const WorkspaceReport r = evaluate_workspace(c, 0);
  EXPECT_FALSE(r.pass);
  ASSERT_FALSE(r.reasons.empty());
  EXPECT_NE(r.reasons[0].find("walls[0]: an attractor's point (0, 0, 0.3) m lies outside "
                              "device.kinematics.workspace"),
            std::string::npos)
      << r.reasons[0];
}

// On a delta, where B_c changes with the configuration: no configuration the grid never saw,
// in no direction, has less damping than the attractor's worst.
TEST(AttractorGate, OnTheDeltaNoPointOrDirectionTheGridMissedHasLessDampingThanItsWorst) {
  const config::Config c = config::load_config_text(
      "device:\n  damping: 0.05\n  kinematics: {kind: delta}\nwalls:\n"
      "  - {kind: attractor, point: [0, 0, 0.11], stiffness: 300, damping: 0.1}\n",
      "attractor.yaml");
  const WorkspaceReport r = evaluate_workspace(c, 0);
  ASSERT_EQ(r.walls.size(), 1u);
  const WallVerdict& v = r.walls[0];
  EXPECT_LE(v.worst_damping, v.grid_worst_damping);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  const kinematics::Box& box = c.device.kinematics.delta.workspace;
  int checked = 0;
  for (int i = 0; i < 3000; ++i) {
    Vec3 x;
    for (int a = 0; a < 3; ++a) x[a] = box.lower[a] + u(rng) * (box.upper[a] - box.lower[a]);
    const kinematics::JointSolution q = kinematics::inverse(c.device.kinematics, x);
    if (q.status != kinematics::Status::kOk) continue;
    const kinematics::Pose p = kinematics::forward(c.device.kinematics, q.q, x);
    const analysis::DeviceDamping d{p.J, Vec3::Constant(0.05), 3, 3};
    const Vec3 n(g(rng), g(rng), g(rng));
    EXPECT_GE(analysis::normal_damping(d, n.normalized()), v.worst_damping * (1.0 - 1e-9))
        << x.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 2500);
  // And it is lambda_min: along its own worst direction at its worst point, exactly that.
  const kinematics::JointSolution q = kinematics::inverse(c.device.kinematics, v.worst_position);
  const kinematics::Pose p = kinematics::forward(c.device.kinematics, q.q, v.worst_position);
  EXPECT_NEAR(analysis::contact_margin({p.J, Vec3::Constant(0.05), 3, 3}, {}), v.worst_damping,
              1e-12);
}

}  // namespace
}  // namespace hapticd::gate
