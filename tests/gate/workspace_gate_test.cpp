// The gate over a workspace (gate/workspace_gate.h) against what can be worked out by hand on
// a gantry (J constant: b_n = 1 / sum n_i^2 s_i^2 / b), the matrix condition at an edge whose
// walls each pass alone, and on the Falcon's delta, against samples the grid never saw.
#include "gate/workspace_gate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "analysis/normal_passivity.h"
#include "config/config_loader.h"
#include "gate/gate.h"
#include "kinematics/kinematics.h"

namespace hapticd::gate {
namespace {

using kinematics::Vec3;

config::Config gantry_walls(const std::string& walls, const std::string& extra = "") {
  return config::load_config_text(R"(device:
  damping: 2
  kinematics: {kind: cartesian, joints: 2, scale: [0.5, 2])" +
                                      extra + R"(}
walls:
)" + walls,
                                  "t.yaml");
}

TEST(WorkspaceGate, AGantrysDampingAlongANormalIsWhatItsScalesMakeIt) {
  const config::Config c = gantry_walls(
      "  - {point: [0.01, 0], normal: [1, 0], stiffness: 100}\n"
      "  - {point: [0, 0.01], normal: [1, 1], stiffness: 100}\n");
  const WorkspaceReport r = evaluate_workspace(c, 0);
  ASSERT_EQ(r.walls.size(), 2u);
  EXPECT_TRUE(r.configuration_independent);
  // x = 0.5 q: b_n = b / s^2 = 2 / 0.25 = 8; the diagonal: 1 / ((0.25 + 4) / 2 / 2) = 0.941.
  EXPECT_NEAR(r.walls[0].worst_damping, 8.0, 1e-12);
  EXPECT_NEAR(r.walls[1].worst_damping, 1.0 / (0.5 * (0.25 + 4.0) / 2.0), 1e-12);
  EXPECT_EQ(r.neighbour_change, 0.0);
  EXPECT_TRUE(r.pass) << (r.reasons.empty() ? "" : r.reasons[0]);
}

// device.damping per joint: B_j = diag(b_0, b_1), so b_n = 1 / sum n_i^2 s_i^2 / b_i; the
// weaker joint's damping bounds a wall along it, and a diagonal wall sees both.
TEST(WorkspaceGate, EachJointsOwnDampingIsItsShareOfTheDampingAlongANormal) {
  config::Config c = gantry_walls(
      "  - {point: [0.01, 0], normal: [1, 0], stiffness: 100}\n"
      "  - {point: [0, 0.01], normal: [0, 1], stiffness: 100}\n"
      "  - {point: [0, 0.01], normal: [1, 1], stiffness: 100}\n");
  c.device.damping[0] = 2.0;
  c.device.damping[1] = 32.0;
  const WorkspaceReport r = evaluate_workspace(c, 0);
  ASSERT_EQ(r.walls.size(), 3u);
  EXPECT_EQ(r.joint_damping, (std::vector<double>{2.0, 32.0}));
  EXPECT_NEAR(r.walls[0].worst_damping, 2.0 / 0.25, 1e-12);
  EXPECT_NEAR(r.walls[1].worst_damping, 32.0 / 4.0, 1e-12);
  EXPECT_NEAR(r.walls[2].worst_damping, 1.0 / (0.5 * (0.25 / 2.0 + 4.0 / 32.0)), 1e-12);
}

TEST(WorkspaceGate, ATooStiffWallIsRefusedWithTheStiffnessThatPassesAndThatOnePasses) {
  const std::string wall = "  - {point: [0, 0.01], normal: [0, 1], stiffness: STIFF}\n";
  auto with = [&](const std::string& k) {
    std::string w = wall;
    w.replace(w.find("STIFF"), 5, k);
    return gantry_walls(w);
  };
  // Along y, x = 2 q: b_n = 2 / 4 = 0.5 N s/m; backward Euler at T = 1 ms: b_req = K T / 2.
  const WorkspaceReport r = evaluate_workspace(with("2000"), 0);
  ASSERT_FALSE(r.pass);
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_NE(r.reasons[0].find("walls[0].stiffness must be <= 900"), std::string::npos)
      << r.reasons[0];
  EXPECT_TRUE(evaluate_workspace(with("900"), 0).pass);
  EXPECT_FALSE(evaluate_workspace(with("905"), 0).pass);
}

TEST(WorkspaceGate, AnEdgeWhoseWallsEachPassAloneCanStillFailTogether) {
  // Two walls at 10 degrees to each other along y: each demands b_req = 0.25 N s/m of the
  // 0.5 the gantry has along y; together, near-parallel, they demand almost twice that.
  const config::Config c = gantry_walls(
      "  - {point: [0, 0.01], normal: [0, 1], stiffness: 500}\n"
      "  - {point: [0, 0.01], normal: [0.17364817766693, 0.98480775301221], stiffness: 500}\n");
  const WorkspaceReport r = evaluate_workspace(c, 0);
  EXPECT_TRUE(r.walls[0].passive);
  EXPECT_TRUE(r.walls[1].passive);
  EXPECT_LT(r.corner_margin, 0.0);
  EXPECT_FALSE(r.pass);
  // Opposite faces of a slab never act together.
  const WorkspaceReport slab =
      evaluate_workspace(gantry_walls("  - {point: [0, 0.01], normal: [0, 1], stiffness: 500}\n"
                                      "  - {point: [0, -0.01], normal: [0, -1], stiffness: 500}\n"),
                         0);
  EXPECT_TRUE(std::isinf(slab.corner_margin)) << slab.corner_margin;
  EXPECT_TRUE(slab.pass);
}

config::Config falcon_walls() {
  std::string walls;
  for (const char* w :
       {"[0.03, 0, 0.11], normal: [1, 0, 0]", "[-0.03, 0, 0.11], normal: [-1, 0, 0]",
        "[0, 0.03, 0.11], normal: [0, 1, 0]", "[0, -0.03, 0.11], normal: [0, -1, 0]",
        "[0, 0, 0.14], normal: [0, 0, 1]", "[0, 0, 0.08], normal: [0, 0, -1]"}) {
    walls += std::string("  - {point: ") + w + ", stiffness: 500}\n";
  }
  return config::load_config_text(
      "device:\n  damping: 0.05\n  kinematics: {kind: delta}\nwalls:\n" + walls, "t.yaml");
}

TEST(WorkspaceGate, OnTheDeltaNoPointTheGridMissedHasLessDampingThanItsWorst) {
  const config::Config c = falcon_walls();
  const WorkspaceReport r = evaluate_workspace(c, 0);
  ASSERT_EQ(r.walls.size(), 6u);
  EXPECT_FALSE(r.configuration_independent);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const kinematics::Box& box = c.device.kinematics.delta.workspace;
  for (std::size_t w = 0; w < r.walls.size(); ++w) {
    const WallVerdict& v = r.walls[w];
    ASSERT_TRUE(v.reached);
    EXPECT_LE(v.worst_damping, v.grid_worst_damping);  // the refinement only ever goes lower
    for (int i = 0; i < 3000; ++i) {
      Vec3 x;
      for (int a = 0; a < 3; ++a) x[a] = box.lower[a] + u(rng) * (box.upper[a] - box.lower[a]);
      if (c.walls[w].normal.dot(x - c.walls[w].point) < 0.0) continue;  // the wall acts here
      const kinematics::JointSolution q = kinematics::inverse(c.device.kinematics, x);
      if (q.status != kinematics::Status::kOk) continue;
      const kinematics::Pose p = kinematics::forward(c.device.kinematics, q.q, x);
      analysis::DeviceDamping d{p.J, Vec3::Constant(0.05), 3, 3};
      EXPECT_GE(analysis::normal_damping(d, c.walls[w].normal), v.worst_damping * (1.0 - 1e-9))
          << "wall " << w << " at " << x.transpose();
    }
  }
}

TEST(WorkspaceGate, ADeltaWithoutAFiniteWorkspaceCannotBeProven) {
  config::Config c = falcon_walls();
  c.device.kinematics.delta.workspace.upper.z() = std::numeric_limits<double>::infinity();
  const WorkspaceReport r = evaluate_workspace(c, 0);
  EXPECT_FALSE(r.pass);
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_NE(r.reasons[0].find("its workspace must be a finite box"), std::string::npos);
}

// A box bigger than the mechanism's reach would be sampled mostly where the device cannot be:
// refused by name, with the first configuration that is not a pose.
TEST(WorkspaceGate, AWorkspaceBeyondTheMechanismsReachIsRefused) {
  config::Config c = falcon_walls();
  c.device.kinematics.delta.workspace.lower = Vec3(-1, -1, -1);
  c.device.kinematics.delta.workspace.upper = Vec3(1, 1, 1);
  const WorkspaceReport r = evaluate_workspace(c, 0);
  EXPECT_FALSE(r.pass);
  EXPECT_GT(r.outside, 4000);
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_NE(r.reasons[0].find("sampled configurations are not a pose of the mechanism (the first "
                              "at x = (-1, -1, -1) m: outside workspace)"),
            std::string::npos)
      << r.reasons[0];
}

// The default boxes lie where their mechanisms work, faces included: a sample exactly on a
// face comes back from inverse and forward kinematics a rounding error outside it, and the
// pantograph's x faces did, until the grid's outermost samples moved a billionth inside.
TEST(WorkspaceGate, EveryDefaultWorkspaceIsPosesToItsFaces) {
  for (const char* kind : {"pantograph", "delta"}) {
    const config::Config c = config::load_config_text(
        std::string("device: {kinematics: {kind: ") + kind + "}}\nwalls: []\n", "t.yaml");
    const WorkspaceReport r = evaluate_workspace(c, 0);
    EXPECT_EQ(r.outside, 0) << kind << ": " << (r.reasons.empty() ? "" : r.reasons[0]);
    EXPECT_TRUE(r.pass) << kind;
  }
}

TEST(WorkspaceGate, TheGateUsesItForSeveralAxesAndNotTheOneJointsWall) {
  const GateReport g = evaluate_gate(falcon_walls(), 1);
  ASSERT_TRUE(g.workspace.has_value());
  EXPECT_TRUE(g.pass) << (g.reasons.empty() ? "" : g.reasons[0]);
  EXPECT_EQ(g.delay_samples, 1);  // the driver's; each wall adds its own
  EXPECT_FALSE(evaluate_gate(config::Config{}, 0).workspace.has_value());
}

}  // namespace
}  // namespace hapticd::gate
