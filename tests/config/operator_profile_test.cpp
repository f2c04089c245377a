// The simulated operator: its kinds, the keys each kind takes, and the time profiles (each
// shape's breakpoints are what the simulator will follow).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "config_test_util.h"

namespace hapticd::config::testing {
namespace {

// A hand operator whose set-point is the given flow mapping.
ProfileSpec setpoint_of(const std::string& profile) {
  return load_config_text("device:\n  sim:\n    operator:\n      setpoint: " + profile + "\n",
                          "t.yaml")
      .device.sim.op.setpoint;
}

// "t.yaml:N" for the line of config/sim.yaml that starts with `line_start`.
std::string at(std::string_view line_start) {
  const std::string_view text = embedded_default_yaml();
  // Built by append: GCC 12 at -O3 warns falsely (-Wrestrict) about "\n" + std::string.
  std::string needle(1, '\n');
  needle.append(line_start);
  const std::size_t pos = text.find(needle);
  EXPECT_NE(pos, std::string_view::npos) << line_start;
  return "t.yaml:" + std::to_string(2 + std::count(text.begin(), text.begin() + pos, '\n'));
}

void expect_points(const ProfileSpec& p, const std::vector<ProfilePoint>& expected) {
  ASSERT_EQ(p.points.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_DOUBLE_EQ(p.points[i].t_s, expected[i].t_s) << "point " << i;
    EXPECT_DOUBLE_EQ(p.points[i].value, expected[i].value) << "point " << i;
  }
}

TEST(Profile, Constant) {
  const ProfileSpec p = setpoint_of("{shape: constant, value: 0.004}");
  EXPECT_EQ(p.shape, ProfileSpec::Shape::kConstant);
  expect_points(p, {{0.0, 0.004}});
}

TEST(Profile, StepIsAJumpAtOneInstant) {
  const ProfileSpec p = setpoint_of("{shape: step, initial: -0.01, final: 0.02, at: 0.5}");
  EXPECT_EQ(p.shape, ProfileSpec::Shape::kStep);
  expect_points(p, {{0.5, -0.01}, {0.5, 0.02}});
}

TEST(Profile, Ramp) {
  expect_points(setpoint_of("{shape: ramp, initial: 0, final: 1, start: 0.2, duration: 0.3}"),
                {{0.2, 0.0}, {0.5, 1.0}});
  // start defaults to 0.
  expect_points(setpoint_of("{shape: ramp, initial: 1, final: 3, duration: 2}"),
                {{0.0, 1.0}, {2.0, 3.0}});
}

TEST(Profile, Sine) {
  const ProfileSpec p =
      setpoint_of("{shape: sine, offset: 0.001, amplitude: 0.002, frequency_hz: 3, phase: 1.5}");
  EXPECT_EQ(p.shape, ProfileSpec::Shape::kSine);
  EXPECT_TRUE(p.points.empty());
  EXPECT_EQ(p.offset, 0.001);
  EXPECT_EQ(p.amplitude, 0.002);
  EXPECT_EQ(p.frequency_hz, 3.0);
  EXPECT_EQ(p.phase_rad, 1.5);
  const ProfileSpec d = setpoint_of("{shape: sine, amplitude: 0.002, frequency_hz: 3}");
  EXPECT_EQ(d.offset, 0.0);
  EXPECT_EQ(d.phase_rad, 0.0);
}

TEST(Profile, PressPushesInHoldsAndWithdraws) {
  const ProfileSpec p = load_embedded_default().device.sim.op.setpoint;
  EXPECT_EQ(p.shape, ProfileSpec::Shape::kPress);
  expect_points(p, {{0.5, -0.02}, {1.0, 0.01}, {2.0, 0.01}, {2.5, -0.02}});
  expect_points(setpoint_of("{shape: press, rest: 0, depth: 1, ramp: 1, hold: 0}"),
                {{0.0, 0.0}, {1.0, 1.0}, {1.0, 1.0}, {2.0, 0.0}});
}

TEST(Profile, KeysOfAnotherShapeAreNotUsed) {
  EXPECT_EQ(errors_of(embedded_default_yaml(), sets({"device.sim.operator.setpoint.amplitude=1"})),
            Lines{"--set device.sim.operator.setpoint.amplitude=1: "
                  "device.sim.operator.setpoint.amplitude: not used by shape 'press'"});
}

TEST(Profile, MissingKeysOfTheShape) {
  const char* yaml =
      "device:\n"
      "  sim:\n"
      "    operator:\n"
      "      setpoint:\n"  // 4
      "        shape: step\n"
      "        initial: 0\n";
  EXPECT_EQ(errors_of(yaml),
            (Lines{"t.yaml:4: device.sim.operator.setpoint.final: missing (required by shape "
                   "'step')",
                   "t.yaml:4: device.sim.operator.setpoint.at: missing (required by shape "
                   "'step')"}));
}

TEST(Profile, ShapeIsRequiredAndChecked) {
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      setpoint: {value: 1}\n"),
            Lines{"t.yaml:4: device.sim.operator.setpoint.shape: missing; must be one of "
                  "constant, step, ramp, sine, press"});
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      setpoint: {shape: square}\n"),
            Lines{"t.yaml:4: device.sim.operator.setpoint.shape: must be one of constant, step, "
                  "ramp, sine, press; got 'square'"});
}

TEST(Profile, UnknownKeySuggestsFromTheShapesKeys) {
  EXPECT_EQ(errors_of(embedded_default_yaml(), sets({"device.sim.operator.setpoint.dept=0.02"})),
            Lines{"--set device.sim.operator.setpoint.dept=0.02: "
                  "device.sim.operator.setpoint.dept: unknown key (did you mean 'depth'?)"});
  EXPECT_EQ(errors_of(embedded_default_yaml(), sets({"device.sim.operator.setpoint.speed=1"})),
            Lines{"--set device.sim.operator.setpoint.speed=1: "
                  "device.sim.operator.setpoint.speed: unknown key; expected one of: shape, rest, "
                  "depth, start, ramp, hold"});
}

TEST(Profile, RangesOfTimes) {
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      setpoint:\n        shape: press\n"
                      "        rest: 0\n        depth: 1\n        ramp: 0\n        hold: -1\n"),
            (Lines{"t.yaml:8: device.sim.operator.setpoint.ramp: must be > 0, got '0'",
                   "t.yaml:9: device.sim.operator.setpoint.hold: must be >= 0, got '-1'"}));
}

TEST(Operator, AbsentKeepsTheDefaults) {
  const OperatorSpec op = load_config_text("device:\n  mass: 0.2\n", "t").device.sim.op;
  const OperatorSpec expected;
  EXPECT_EQ(op.kind, expected.kind);
  EXPECT_EQ(op.stiffness, expected.stiffness);
  EXPECT_EQ(op.damping, expected.damping);
}

TEST(Operator, HandRequiresASetPoint) {
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      kind: hand\n      stiffness: 200\n"),
            Lines{"t.yaml:3: device.sim.operator.setpoint: missing (required by operator kind "
                  "'hand')"});
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      stiffness: 0\n"
                      "      setpoint: {shape: constant, value: 0}\n"),
            Lines{"t.yaml:4: device.sim.operator.stiffness: must be > 0, got '0'"});
}

TEST(Operator, ForceTakesAForceProfile) {
  const OperatorSpec op = load_config_text(
                              "device:\n  sim:\n    operator:\n      kind: force\n"
                              "      force: {shape: step, initial: 0, final: 1.5, at: 0.1}\n",
                              "t")
                              .device.sim.op;
  EXPECT_EQ(op.kind, OperatorSpec::Kind::kForce);
  expect_points(op.force, {{0.1, 0.0}, {0.1, 1.5}});
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      kind: force\n"),
            Lines{"t.yaml:3: device.sim.operator.force: missing (required by operator kind "
                  "'force')"});
}

TEST(Operator, KeysOfAnotherKindAreNotUsed) {
  EXPECT_EQ(errors_of(embedded_default_yaml(),
                      sets({"device.sim.operator.kind=force",
                            "device.sim.operator.force={shape: constant, value: 1}"})),
            (Lines{at("      stiffness: 300") +
                       ": device.sim.operator.stiffness: not used by operator kind 'force'",
                   at("      damping: 5") +
                       ": device.sim.operator.damping: not used by operator kind 'force'",
                   at("      setpoint:") +
                       ": device.sim.operator.setpoint: not used by operator kind 'force'"}));
}

TEST(Operator, Motion) {
  const OperatorSpec op =
      load_config_text(
          "device:\n  sim:\n    operator:\n      kind: motion\n      offset: 0.01\n"
          "      amplitude: 0.002\n      frequency_hz: 5\n",
          "t")
          .device.sim.op;
  EXPECT_EQ(op.kind, OperatorSpec::Kind::kMotion);
  EXPECT_EQ(op.motion.offset, 0.01);
  EXPECT_EQ(op.motion.amplitude, 0.002);
  EXPECT_EQ(op.motion.frequency_hz, 5.0);
  EXPECT_EQ(op.motion.phase_rad, 0.0);
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      kind: motion\n      offset: 0\n"
                      "      amplitude: 0.002\n"),
            Lines{"t.yaml:3: device.sim.operator.frequency_hz: missing (required by operator "
                  "kind 'motion')"});
}

TEST(Operator, MotionFrequencyIsBelowNyquist) {
  const std::string motion =
      "device:\n  sim:\n    operator:\n      kind: motion\n      offset: 0\n"
      "      amplitude: 0.001\n      frequency_hz: 600\n";  // frequency on line 7
  EXPECT_EQ(errors_of(motion), Lines{"t.yaml:7: device.sim.operator.frequency_hz: must be <= the "
                                     "Nyquist frequency rate_hz/2 = 500, got '600'"});
  // The limit follows the configured rate.
  EXPECT_EQ(
      load_config_text(motion, "t", sets({"loop.rate_hz=2000"})).device.sim.op.motion.frequency_hz,
      600.0);
}

TEST(Operator, ReplayLogResolvesAgainstTheConfigDirectory) {
  const std::string yaml =
      "device:\n  sim:\n    operator:\n      kind: replay\n      log: runs/../run1.hlog\n";
  EXPECT_EQ(load_config_text(yaml, "t", {}, "/data/cfg").device.sim.op.replay_log,
            "/data/cfg/run1.hlog");
  EXPECT_EQ(
      load_config_text(yaml, "t", sets({"device.sim.operator.log=/var/log/x.hlog"}), "/data/cfg")
          .device.sim.op.replay_log,
      "/var/log/x.hlog");
  // A relative base (the file's directory as given) still yields an absolute path.
  EXPECT_EQ(load_config_text(yaml, "t", {}, "cfg").device.sim.op.replay_log,
            (std::filesystem::current_path() / "cfg/run1.hlog").string());
}

TEST(Operator, ReplayPathInEffectiveYamlIsAbsolute) {
  // The effective document travels in tick logs; loaded from elsewhere it must name the
  // same log.
  const Config c =
      load_config_text("device:\n  sim:\n    operator:\n      kind: replay\n      log: run1.hlog\n",
                       "t", {}, "/data/cfg");
  EXPECT_EQ(
      load_config_text(c.effective_yaml, "log header", {}, "/elsewhere").device.sim.op.replay_log,
      "/data/cfg/run1.hlog");
}

TEST(Operator, ReplayNeedsALog) {
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      kind: replay\n"),
            Lines{"t.yaml:3: device.sim.operator.log: missing (required by operator kind "
                  "'replay')"});
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      kind: replay\n      log: \"\"\n"),
            Lines{"t.yaml:5: device.sim.operator.log: must be the path of a tick log, got "
                  "nothing"});
}

TEST(Operator, BadKindIsReportedAlone) {
  // With no valid kind nothing says which keys apply, so only the kind is reported.
  EXPECT_EQ(errors_of("device:\n  sim:\n    operator:\n      kind: robot\n      stiffness: 1\n"),
            Lines{"t.yaml:4: device.sim.operator.kind: must be one of hand, force, motion, "
                  "replay; got 'robot'"});
}

}  // namespace
}  // namespace hapticd::config::testing
