// device.kinematics as a user writes it: each kind with its own keys, the numbers reaching the
// kinematics they describe, and every mistake named by file, line and key - another kind's
// key, a list of the wrong length, a sign that is not one, a mechanism that cannot exist.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "config_test_util.h"

namespace hapticd::config::testing {
namespace {

using kinematics::Kind;

TEST(KinematicsConfig, AbsentIsOneJointAsBefore) {
  const Config c = load_config_text("wall: {stiffness: 1000}\n", "t.yaml");
  EXPECT_EQ(c.device.kinematics.kind, Kind::kJoints);
  EXPECT_EQ(kinematics::joint_count(c.device.kinematics), 1);
}

TEST(KinematicsConfig, ACartesianGantryReadsItsScalesSignsAndBox) {
  const Config c = load_config_text(R"(device:
  kinematics:
    kind: cartesian
    joints: 2
    scale: [0.01, 0.02]
    sign: [1, -1]
    workspace: {lower: [-0.1, -0.2], upper: [0.1, 0.2]}
)",
                                    "t.yaml");
  const kinematics::CartesianParams& p = c.device.kinematics.cartesian;
  EXPECT_EQ(c.device.kinematics.kind, Kind::kCartesian);
  EXPECT_EQ(p.n, 2);
  EXPECT_EQ(p.scale[1], 0.02);
  EXPECT_EQ(p.sign[1], -1.0);
  EXPECT_EQ(p.workspace.upper[1], 0.2);
  // The numbers reach the mechanism: joint 1 at 10 units is 0.2 m the other way.
  const kinematics::Pose pose =
      kinematics::forward(c.device.kinematics, {0.0, 10.0, 0.0}, kinematics::Vec3::Zero());
  EXPECT_DOUBLE_EQ(pose.x[1], -0.2);
}

TEST(KinematicsConfig, ADeltaTakesItsGeometryAndArmAnglesInDegrees) {
  const Config c = load_config_text(R"(device:
  kinematics:
    kind: delta
    thigh: 0.07
    arm_angle_deg: [105, -15, -135]
)",
                                    "t.yaml");
  const kinematics::DeltaParams& d = c.device.kinematics.delta;
  EXPECT_EQ(kinematics::joint_count(c.device.kinematics), 3);
  EXPECT_EQ(d.thigh, 0.07);
  EXPECT_EQ(d.shin, kinematics::DeltaParams{}.shin);  // unset: the Falcon's
  EXPECT_NEAR(d.arm_angle[2], -135.0 * std::numbers::pi / 180.0, 1e-15);
}

TEST(KinematicsConfig, AnotherKindsKeyIsRefusedByName) {
  const Lines e = errors_of(R"(device:
  kinematics:
    kind: pantograph
    scale: [1, 1]
)");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0],
            "t.yaml:4: device.kinematics.scale: not used by device.kinematics.kind pantograph");
}

TEST(KinematicsConfig, ListsOfTheWrongLengthAndBadSignsAreNamed) {
  const Lines e = errors_of(R"(device:
  kinematics:
    kind: cartesian
    joints: 3
    scale: [1, 1]
    sign: [1, 0.5, -1]
)");
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0], "t.yaml:5: device.kinematics.scale: must hold 3 numbers, got 2");
  EXPECT_EQ(e[1], "t.yaml:6: device.kinematics.sign[1]: must be +1 or -1, got 0.5");
}

TEST(KinematicsConfig, TooManyJointsAndAnUnknownKindAreRefused) {
  EXPECT_EQ(errors_of("device: {kinematics: {kind: joints, joints: 4}}\n"),
            Lines{"t.yaml:1: device.kinematics.joints: must be in 1..3, got '4'"});
  const Lines e = errors_of("device: {kinematics: {kind: scara}}\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(
      e[0].find("device.kinematics.kind: must be one of joints, cartesian, pantograph, delta"),
      std::string::npos)
      << e[0];
}

// A gantry of two different drives: each joint its own mass, damping and limit, or one number
// for all; the list's length is the kinematics' joint count, whatever order the keys come in.
TEST(KinematicsConfig, MassDampingAndMaxForceAreOneNumberOrOnePerJoint) {
  const Config c = load_config_text(R"(device:
  max_force: [3, 1.5]
  mass: 0.4
  damping: [2, 8]
  kinematics: {kind: cartesian, joints: 2}
)",
                                    "t.yaml");
  EXPECT_EQ(c.device.max_force[0], 3.0);
  EXPECT_EQ(c.device.max_force[1], 1.5);
  EXPECT_EQ(c.device.mass[0], 0.4);
  EXPECT_EQ(c.device.mass[1], 0.4);
  EXPECT_EQ(c.device.damping.per_joint().head<2>(), kinematics::Vec3(2, 8, 0).head<2>());
  EXPECT_EQ(load_config_text("device: {mass: [0.3]}\n", "t.yaml").device.mass[0], 0.3)
      << "one joint: a list of one";
}

TEST(KinematicsConfig, APerJointListOfTheWrongLengthOrABadNumberIsNamed) {
  const Lines e = errors_of(R"(device:
  max_force: [3, 1.5, 2]
  damping: [2, -1]
  kinematics: {kind: cartesian, joints: 2}
  mass: []
)");
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0],
            "t.yaml:2: device.max_force: must be one number (every joint's) or a list of one "
            "per joint: device.kinematics has 2 joints, got 3 numbers");
  EXPECT_EQ(e[1], "t.yaml:3: device.damping[1]: must be > 0, got '-1'");
  EXPECT_EQ(e[2],
            "t.yaml:5: device.mass: must be one number (every joint's) or a list of one per "
            "joint: device.kinematics has 2 joints, got 0 numbers");
  EXPECT_EQ(errors_of("device: {max_force: [1, 2]}\n"),
            Lines{"t.yaml:1: device.max_force: must be one number (every joint's) or a list of "
                  "one per joint: device.kinematics has 1 joint, got 2 numbers"});
}

TEST(KinematicsConfig, AMechanismThatCannotExistIsRefusedWithTheReason) {
  const Lines e = errors_of(R"(device:
  kinematics:
    kind: delta
    workspace: {lower: [0, 0, 0.1], upper: [0.05, 0.05, 0.1]}
)");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0],
            "t.yaml:2: device.kinematics: describes no mechanism: delta: empty workspace box");
}

}  // namespace
}  // namespace hapticd::config::testing
