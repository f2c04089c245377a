// --set key.path=value: parsing the argument, merging it before validation, and naming the
// argument (not a line of the file) when its value is wrong.
#include <gtest/gtest.h>

#include "config_test_util.h"

namespace hapticd::config::testing {
namespace {

TEST(ParseOverride, SplitsAtTheFirstEquals) {
  const Override o = parse_override("device.sim.operator.log=runs/a=b.hlog");
  EXPECT_EQ(o.key_path, "device.sim.operator.log");
  EXPECT_EQ(o.value, "runs/a=b.hlog");
  EXPECT_EQ(o.text, "device.sim.operator.log=runs/a=b.hlog");
  EXPECT_EQ(parse_override("telemetry.log=").value, "");
}

TEST(ParseOverride, MalformedArgumentsAreRefused) {
  for (const char* arg : {"wall.stiffness", "=5", "wall..stiffness=5", ".wall=1", "wall.=1", ""}) {
    try {
      parse_override(arg);
      ADD_FAILURE() << "accepted '" << arg << "'";
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.messages(), Lines{"--set " + std::string(arg) + ": expected key.path=value"});
    }
  }
}

TEST(Set, Number) {
  const Config c = load_embedded_default(sets({"wall.stiffness=2500"}));
  EXPECT_EQ(c.wall.stiffness, 2500.0);
  EXPECT_EQ(c.wall.damping, 0.2);  // neighbours untouched
}

TEST(Set, ListsParseAsYaml) {
  const Config c = load_embedded_default(
      sets({"wall.coupling.numerator=[0.1,-0.07]", "wall.coupling.denominator=[1, -0.9]"}));
  ASSERT_TRUE(c.wall.coupling.present);
  EXPECT_EQ(c.wall.coupling.numerator, (Coefficients{0.1, -0.07}));
  EXPECT_EQ(c.wall.coupling.denominator, (Coefficients{1.0, -0.9}));
}

TEST(Set, Bool) {
  EXPECT_TRUE(load_embedded_default(sets({"wall.no_pull=true"})).wall.no_pull);
  EXPECT_FALSE(
      load_config_text("wall:\n  no_pull: true\n", "t", sets({"wall.no_pull=no"})).wall.no_pull);
}

TEST(Set, CreatesMissingIntermediateMappings) {
  const Config c = load_config_text(
      "", "t.yaml", sets({"device.sim.initial_position=0.005", "analysis.operator.stiffness=450"}));
  EXPECT_EQ(c.device.sim.initial_position, 0.005);
  EXPECT_EQ(c.analysis.operator_stiffness, 450.0);
}

TEST(Set, ReplacesAWholeMapping) {
  const Config c = load_embedded_default(
      sets({"device.sim.operator={kind: force, force: {shape: constant, value: 2}}"}));
  EXPECT_EQ(c.device.sim.op.kind, OperatorSpec::Kind::kForce);
  ASSERT_EQ(c.device.sim.op.force.points.size(), 1u);
  EXPECT_EQ(c.device.sim.op.force.points[0].value, 2.0);
}

TEST(Set, AppliesBeforeValidationSoItCanFixABadFile) {
  EXPECT_EQ(
      load_config_text("wall:\n  stiffness: -1\n", "t", sets({"wall.stiffness=5"})).wall.stiffness,
      5.0);
}

TEST(Set, LaterSetWins) {
  EXPECT_EQ(load_embedded_default(sets({"wall.stiffness=1", "wall.stiffness=3"})).wall.stiffness,
            3.0);
}

TEST(Set, WrongTypeNamesTheArgument) {
  EXPECT_EQ(errors_of("wall:\n  stiffness: 1\n", sets({"wall.stiffness=abc"})),
            Lines{"--set wall.stiffness=abc: wall.stiffness: must be a number, got 'abc'"});
  EXPECT_EQ(
      errors_of("", sets({"wall.coupling.numerator=[0.1, x]", "wall.coupling.denominator=[1]"})),
      Lines{"--set wall.coupling.numerator=[0.1, x]: wall.coupling.numerator[1]: must be a "
            "number, got 'x'"});
}

// An element of a list the document has: walls[1].stiffness sets that wall's alone (safety.gate:
// derate records the walls it lowered this way); an element it does not have is named.
TEST(Set, AnElementOfAListIsSetByItsIndex) {
  const std::string walls =
      "device: {kinematics: {kind: cartesian, joints: 2}}\n"
      "walls:\n  - {point: [0.01, 0], normal: [1, 0], stiffness: 100}\n"
      "  - {point: [0, 0.01], normal: [0, 1], stiffness: 200}\n";
  const Config c = load_config_text(walls, "t", sets({"walls[1].stiffness=250"}));
  EXPECT_EQ(c.walls[0].law.stiffness, 100.0);
  EXPECT_EQ(c.walls[1].law.stiffness, 250.0);
  EXPECT_EQ(errors_of(walls, sets({"walls[2].stiffness=5"})),
            Lines{"--set walls[2].stiffness=5: walls[2]: no such mapping to set 'stiffness' "
                  "inside"});
  EXPECT_EQ(errors_of(walls, sets({"walls[7]=5"})),
            Lines{"--set walls[7]=5: walls[7]: no such element of a list to set"});
}

TEST(Set, UnknownKeyNamesTheArgument) {
  EXPECT_EQ(errors_of("", sets({"wall.stifness=5"})),
            Lines{"--set wall.stifness=5: wall.stifness: unknown key (did you mean 'stiffness'?)"});
  // An unknown section it had to create is reported once, at the section.
  EXPECT_EQ(errors_of("", sets({"wal.stiffness=5"})),
            Lines{"--set wal.stiffness=5: wal: unknown key (did you mean 'wall'?)"});
}

TEST(Set, MappingItCreatedIsReportedAgainstIt) {
  // The default file has no coupling, so this --set made the mapping and owns its problems.
  EXPECT_EQ(errors_of(embedded_default_yaml(), sets({"wall.coupling.numerator=[0.1]"})),
            Lines{"--set wall.coupling.numerator=[0.1]: wall.coupling: missing 'denominator'"});
}

TEST(Set, FileErrorsFirstThenSetErrorsInCommandLineOrder) {
  EXPECT_EQ(errors_of("wall:\n  damping: -1\n",
                      sets({"loop.rate_hz=0", "wall.stiffness=-2", "loop.cpu=-3"})),
            (Lines{"t.yaml:2: wall.damping: must be >= 0, got '-1'",
                   "--set loop.rate_hz=0: loop.rate_hz: must be in [1, 100000], got '0'",
                   "--set wall.stiffness=-2: wall.stiffness: must be >= 0, got '-2'",
                   "--set loop.cpu=-3: loop.cpu: must be >= -1, got '-3'"}));
}

TEST(Set, CannotDescendIntoAValue) {
  EXPECT_EQ(errors_of(embedded_default_yaml(), sets({"wall.stiffness.x=1"})),
            Lines{"--set wall.stiffness.x=1: wall.stiffness: cannot set 'x' inside it: it is not "
                  "a mapping"});
}

TEST(Set, ValueThatIsNotYaml) {
  EXPECT_EQ(errors_of("", sets({"wall.coupling.numerator=[0.1"})),
            Lines{"--set wall.coupling.numerator=[0.1: wall.coupling.numerator: value is not "
                  "valid YAML: end of sequence flow not found"});
}

TEST(Set, ProgrammaticOverrideWithoutTextUsesKeyAndValue) {
  EXPECT_EQ(errors_of("", {Override{"wall.damping", "-1", ""}}),
            Lines{"--set wall.damping=-1: wall.damping: must be >= 0, got '-1'"});
}

// What safety.gate: derate records: the validated document with one value changed, read back
// to the same typed configuration as if it had been set so, and to the same value to the bit.
TEST(WithSetting, TheDocumentHoldsTheValueAndEverythingElseAsItWas) {
  const Config c = load_embedded_default(sets({"wall.damping=3"}));
  const std::string yaml =
      with_setting(c.effective_yaml, {"wall.stiffness", "1234.5678901234567", {}});
  const Config back = load_config_text(yaml, "effective");
  EXPECT_EQ(back.wall.stiffness, 1234.5678901234567);
  EXPECT_EQ(back.wall.damping, 3.0);
  EXPECT_EQ(back.loop.rate_hz, c.loop.rate_hz);
  EXPECT_EQ(back.device.sim.op.kind, c.device.sim.op.kind);
}

TEST(WithSetting, AKeyThatCannotBeSetIsRefusedByName) {
  const Config c = load_embedded_default();
  try {
    with_setting(c.effective_yaml, {"wall.stiffness.value", "1", {}});
    FAIL() << "a key below a number was set";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("wall.stiffness"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a mapping"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hapticd::config::testing
