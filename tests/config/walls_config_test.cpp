// `walls` as a user writes it for a device of several task axes, and `wall` for one joint: each
// refuses the other by name, every wall needs a point and a normal of the task's dimension, a
// normal is a direction (normalised) that must point somewhere, and the law reads as `wall`'s;
// an attractor (kind: attractor) has a point, the law and its own max_force, and no normal.
#include <gtest/gtest.h>

#include <cmath>

#include "config_test_util.h"

namespace hapticd::config::testing {
namespace {

constexpr const char* kGantry = R"(device:
  kinematics: {kind: cartesian, joints: 2}
)";

TEST(WallsConfig, AGantrysWallsReadTheirPointNormalAndLaw) {
  const Config c = load_config_text(std::string(kGantry) + R"(walls:
  - {point: [0.02, 0], normal: [1, 1], stiffness: 1500, damping: 1, no_pull: true}
  - {point: [0, -0.03], normal: [0, -2], delay_samples: 2}
)",
                                    "t.yaml");
  ASSERT_EQ(c.walls.size(), 2u);
  EXPECT_EQ(c.walls[0].point.x(), 0.02);
  EXPECT_NEAR(c.walls[0].normal.x(), std::sqrt(0.5), 1e-15);  // normalised
  EXPECT_EQ(c.walls[0].law.stiffness, 1500.0);
  EXPECT_TRUE(c.walls[0].law.no_pull);
  EXPECT_EQ(c.walls[1].normal.y(), -1.0);
  EXPECT_EQ(c.walls[1].law.delay_samples, 2);
  EXPECT_EQ(c.walls[1].law.stiffness, WallConfig{}.stiffness);  // unset: as `wall`'s default
}

TEST(WallsConfig, WallAndWallsEachRefuseTheOtherByName) {
  EXPECT_EQ(errors_of(std::string(kGantry) + "wall: {stiffness: 1000}\n"),
            Lines{"t.yaml:3: wall: not used by device.kinematics kind cartesian (its walls are "
                  "`walls`)"});
  EXPECT_EQ(errors_of("walls: [{point: [0], normal: [1]}]\n"),
            Lines{"t.yaml:1: walls: not used by a device of one joint (its wall is `wall`)"});
}

TEST(WallsConfig, APointOrNormalOfTheWrongSizeOrNoDirectionIsNamed) {
  const Lines e = errors_of(std::string(kGantry) + R"(walls:
  - {point: [0, 0, 0], normal: [1, 0]}
  - {point: [0, 0], normal: [0, 0]}
  - {normal: [1, 0], stifness: 3}
)");
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(e[0], "t.yaml:4: walls[0].point: must hold 2 numbers (one per task axis), got 3");
  EXPECT_EQ(e[1],
            "t.yaml:5: walls[1].normal: must point somewhere (a direction into the wall), got all "
            "zeros");
  EXPECT_NE(e[2].find("walls[2].point: missing"), std::string::npos) << e[2];
  EXPECT_NE(e[3].find("walls[2].stifness: unknown key (did you mean 'stiffness'?)"),
            std::string::npos)
      << e[3];
}

TEST(WallsConfig, AnAttractorIsAPointAndALawWithAnOptionalMaxForce) {
  const Config c = load_config_text(std::string(kGantry) + R"(walls:
  - {kind: attractor, point: [0.01, -0.02], stiffness: 300, damping: 0.5, max_force: 2}
  - {kind: attractor, point: [0, 0]}
  - {kind: wall, point: [0, 0], normal: [1, 0]}
)",
                                    "t.yaml");
  ASSERT_EQ(c.walls.size(), 3u);
  EXPECT_EQ(c.walls[0].kind, WallKind::kAttractor);
  EXPECT_EQ(c.walls[0].point.y(), -0.02);
  EXPECT_EQ(c.walls[0].normal, kinematics::Vec3::Zero());
  EXPECT_EQ(c.walls[0].law.stiffness, 300.0);
  EXPECT_EQ(c.walls[0].max_force, 2.0);
  EXPECT_TRUE(std::isinf(c.walls[1].max_force)) << "none: the joints' limits alone";
  EXPECT_EQ(c.walls[2].kind, WallKind::kWall);
}

TEST(WallsConfig, WhatAnAttractorCannotHaveIsNamed) {
  const Lines e = errors_of(std::string(kGantry) + R"(walls:
  - {kind: attractor, point: [0, 0], normal: [1, 0]}
  - {kind: attractor, point: [0, 0], no_pull: true}
  - {kind: attractor, point: [0, 0], max_force: 0}
  - {point: [0, 0], normal: [1, 0], max_force: 3}
  - {kind: magnet, point: [0, 0], normal: [1, 0]}
)");
  ASSERT_EQ(e.size(), 5u);
  EXPECT_EQ(e[0],
            "t.yaml:4: walls[0].normal: not used by an attractor: it pulls towards its point "
            "along every task axis");
  EXPECT_EQ(e[1],
            "t.yaml:5: walls[1].no_pull: an attractor pulls towards its point: no_pull: true "
            "would leave half of it; use a wall");
  EXPECT_EQ(e[2], "t.yaml:6: walls[2].max_force: must be > 0, got '0'");
  EXPECT_NE(e[3].find("walls[3].max_force: not used by a wall"), std::string::npos) << e[3];
  EXPECT_NE(e[4].find("walls[4].kind"), std::string::npos) << e[4];
  EXPECT_NE(e[4].find("attractor"), std::string::npos) << e[4];
}

TEST(WallsConfig, ANormalOfHugeOrTinyNumbersIsStillItsDirection) {
  const Config c = load_config_text(std::string(kGantry) + R"(walls:
  - {point: [0, 0], normal: [1e300, 1e300]}
  - {point: [0, 0], normal: [0, -1e-320]}
)",
                                    "t.yaml");
  EXPECT_NEAR(c.walls[0].normal.x(), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(c.walls[1].normal.y(), -1.0);
}

TEST(WallsConfig, MoreWallsThanTheLoopHoldsAreRefused) {
  std::string yaml = std::string(kGantry) + "walls:\n";
  for (std::size_t i = 0; i <= kMaxWalls; ++i) yaml += "  - {point: [0, 0], normal: [1, 0]}\n";
  EXPECT_EQ(errors_of(yaml), Lines{"t.yaml:3: walls: at most 8 walls, got 9"});
}

}  // namespace
}  // namespace hapticd::config::testing
