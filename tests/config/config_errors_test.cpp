// Every class of bad configuration produces one exact, located message a person can act on.
#include <gtest/gtest.h>

#include "config/driver_schema.h"
#include "config_test_util.h"

namespace hapticd::config::testing {
namespace {

TEST(ConfigErrors, UnknownKeySuggestsTheCloseSchemaKey) {
  EXPECT_EQ(errors_of("wall:\n  stifness: 10\n"),
            Lines{"t.yaml:2: wall.stifness: unknown key (did you mean 'stiffness'?)"});
  // Transposed letters count as one edit.
  EXPECT_EQ(errors_of("wall:\n  dampnig: 1\n"),
            Lines{"t.yaml:2: wall.dampnig: unknown key (did you mean 'damping'?)"});
  EXPECT_EQ(errors_of("wal:\n  stiffness: 10\n"),
            Lines{"t.yaml:1: wal: unknown key (did you mean 'wall'?)"});
}

TEST(ConfigErrors, UnknownKeyMatchesCaseInsensitively) {
  EXPECT_EQ(errors_of("loop:\n  RATE_HZ: 500\n"),
            Lines{"t.yaml:2: loop.RATE_HZ: unknown key (did you mean 'rate_hz'?)"});
}

TEST(ConfigErrors, UnknownKeyWithoutNeighbourListsTheAllowedKeys) {
  EXPECT_EQ(errors_of("safety:\n  colour: red\n"),
            Lines{"t.yaml:2: safety.colour: unknown key; expected one of: gate, "
                  "operator_passivity_shortage, passivity_margin, max_speed, max_wall_speed, "
                  "client_walls_on_leave, client_force_limit, client_force_hold_ms, "
                  "client_force_ramp_ms, client_force_energy_j, stale_fault_ticks, "
                  "sequence_gap_fault, passivity_controller, passivity_max_damping, "
                  "direction_check, max_penetration"});
  EXPECT_EQ(errors_of("plugins: []\n"),
            Lines{"t.yaml:1: plugins: unknown key; expected one of: loop, device, wall, safety, "
                  "analysis, telemetry"});
}

TEST(ConfigErrors, ValuesOfTheWrongType) {
  EXPECT_EQ(errors_of("wall:\n  stiffness: abc\n"),
            Lines{"t.yaml:2: wall.stiffness: must be a number, got 'abc'"});
  EXPECT_EQ(errors_of("wall:\n  stiffness: [1, 2]\n"),
            Lines{"t.yaml:2: wall.stiffness: must be a number, got a list"});
  EXPECT_EQ(errors_of("wall:\n  stiffness:\n"),
            Lines{"t.yaml:2: wall.stiffness: must be a number, got nothing"});
  EXPECT_EQ(errors_of("loop:\n  rt_priority: 1.5\n"),
            Lines{"t.yaml:2: loop.rt_priority: must be an integer, got '1.5'"});
  EXPECT_EQ(errors_of("wall:\n  no_pull: maybe\n"),
            Lines{"t.yaml:2: wall.no_pull: must be true or false, got 'maybe'"});
  EXPECT_EQ(errors_of("wall: 5\n"), Lines{"t.yaml:1: wall: must be a mapping"});
  EXPECT_EQ(errors_of("telemetry:\n  log: [a.hlog]\n"),
            Lines{"t.yaml:2: telemetry.log: must be a string, got a list"});
  EXPECT_EQ(errors_of("- loop\n"), Lines{"t.yaml:1: the top level must be a mapping"});
}

TEST(ConfigErrors, NonFiniteNumbersAreRefused) {
  EXPECT_EQ(errors_of("wall:\n  position: .nan\n"),
            Lines{"t.yaml:2: wall.position: must be a finite number, got '.nan'"});
  EXPECT_EQ(errors_of("wall:\n  position: .inf\n"),
            Lines{"t.yaml:2: wall.position: must be a finite number, got '.inf'"});
  EXPECT_EQ(errors_of("wall:\n  position: -.inf\n"),
            Lines{"t.yaml:2: wall.position: must be a finite number, got '-.inf'"});
  EXPECT_EQ(errors_of("wall:\n  position: 1e999\n"),
            Lines{"t.yaml:2: wall.position: must be a finite number, got '1e999'"});
}

TEST(ConfigErrors, EnumerationsListTheAllowedValues) {
  EXPECT_EQ(errors_of("wall:\n  discretization: foo\n"),
            Lines{"t.yaml:2: wall.discretization: must be one of backward, tustin; got 'foo'"});
  EXPECT_EQ(errors_of("device:\n  driver: usb\n"),
            Lines{"t.yaml:2: device.driver: must be one of sim; got 'usb'"});
  EXPECT_EQ(errors_of("safety:\n  gate: off\n"),
            Lines{"t.yaml:2: safety.gate: must be one of enforce, warn, derate; got 'off'"});
}

TEST(ConfigErrors, RangesSayWhatIsAllowed) {
  EXPECT_EQ(errors_of("device:\n  mass: -1\n"),
            Lines{"t.yaml:2: device.mass: must be > 0, got '-1'"});
  EXPECT_EQ(errors_of("device:\n  damping: 0\n"),
            Lines{"t.yaml:2: device.damping: must be > 0, got '0'"});
  EXPECT_EQ(errors_of("wall:\n  stiffness: -5\n"),
            Lines{"t.yaml:2: wall.stiffness: must be >= 0, got '-5'"});
  EXPECT_EQ(errors_of("safety:\n  passivity_margin: 1.5\n"),
            Lines{"t.yaml:2: safety.passivity_margin: must be in [0, 1), got '1.5'"});
  EXPECT_EQ(errors_of("safety:\n  passivity_margin: 1\n"),
            Lines{"t.yaml:2: safety.passivity_margin: must be in [0, 1), got '1'"});
  EXPECT_EQ(errors_of("wall:\n  normal: 0\n"),
            Lines{"t.yaml:2: wall.normal: must be +1 or -1, got '0'"});
  EXPECT_EQ(errors_of("loop:\n  rt_priority: 0\n"),
            Lines{"t.yaml:2: loop.rt_priority: must be in 1..99, got '0'"});
  EXPECT_EQ(errors_of("loop:\n  rate_hz: 2e6\n"),
            Lines{"t.yaml:2: loop.rate_hz: must be in [1, 100000], got '2e6'"});
  EXPECT_EQ(errors_of("loop:\n  cpu: -2\n"), Lines{"t.yaml:2: loop.cpu: must be >= -1, got '-2'"});
  EXPECT_EQ(errors_of("loop:\n  overrun_fault_streak: 0\n"),
            Lines{"t.yaml:2: loop.overrun_fault_streak: must be >= 1, got '0'"});
  EXPECT_EQ(errors_of("wall:\n  delay_samples: 101\n"),
            Lines{"t.yaml:2: wall.delay_samples: must be in 0..100, got '101'"});
  EXPECT_EQ(errors_of("telemetry:\n  ring_capacity: 10\n"),
            Lines{"t.yaml:2: telemetry.ring_capacity: must be in 64..4194304, got '10'"});
  // Issue 7: no upper bound meant bad_alloc (exit 1) instead of a configuration error.
  EXPECT_EQ(errors_of("telemetry:\n  ring_capacity: 4294967295\n"),
            Lines{"t.yaml:2: telemetry.ring_capacity: must be in 64..4194304, got '4294967295'"});
  // Issue 7: 1e-320 Hz made T infinite, and the gate passed.
  EXPECT_EQ(errors_of("loop:\n  rate_hz: 0.5\n"),
            Lines{"t.yaml:2: loop.rate_hz: must be in [1, 100000], got '0.5'"});
  EXPECT_EQ(errors_of("device:\n  sim:\n    seed: -1\n"),
            Lines{"t.yaml:3: device.sim.seed: must be >= 0, got '-1'"});
}

TEST(ConfigErrors, BoundaryValuesAreAccepted) {
  const Config c = load_config_text(
      "loop:\n  rate_hz: 100000\n  rt_priority: 99\n  cpu: -1\n"
      "wall:\n  normal: -1\n  stiffness: 0\n  delay_samples: 100\n"
      "safety:\n  passivity_margin: 0\n"
      "telemetry:\n  ring_capacity: 64\n",
      "t.yaml");
  EXPECT_EQ(c.loop.rate_hz, 100000.0);
  EXPECT_EQ(c.loop.rt_priority, 99);
  EXPECT_EQ(c.wall.normal, -1);
  EXPECT_EQ(c.wall.stiffness, 0.0);
  EXPECT_EQ(c.wall.delay_samples, 100);
  EXPECT_EQ(c.safety.passivity_margin, 0.0);
  EXPECT_EQ(c.telemetry.ring_capacity, 64u);
}

TEST(ConfigErrors, CouplingDenominatorMustHaveANonZeroLead) {
  EXPECT_EQ(errors_of("wall:\n  coupling:\n    numerator: [1]\n    denominator: [0, 1]\n"),
            Lines{"t.yaml:4: wall.coupling.denominator: leading coefficient must be non-zero "
                  "(it normalises C(z)), got '0'"});
  EXPECT_EQ(errors_of("analysis:\n  transparency_weight:\n    numerator: [1]\n"
                      "    denominator: [0.0]\n"),
            Lines{"t.yaml:4: analysis.transparency_weight.denominator: leading coefficient must "
                  "be non-zero (it normalises W(z)), got '0.0'"});
}

TEST(ConfigErrors, CouplingNeedsBothLists) {
  EXPECT_EQ(errors_of("wall:\n  coupling:\n    numerator: [1]\n"),
            Lines{"t.yaml:2: wall.coupling: missing 'denominator'"});
  EXPECT_EQ(errors_of("wall:\n  coupling: {}\n"),
            (Lines{"t.yaml:2: wall.coupling: missing 'numerator'",
                   "t.yaml:2: wall.coupling: missing 'denominator'"}));
}

TEST(ConfigErrors, CouplingListsMustHoldNumbers) {
  EXPECT_EQ(errors_of("wall:\n  coupling:\n    numerator: 0.5\n    denominator: [1]\n"),
            Lines{"t.yaml:3: wall.coupling.numerator: must be a list of numbers"});
  EXPECT_EQ(errors_of("wall:\n  coupling:\n    numerator: []\n    denominator: [1]\n"),
            Lines{"t.yaml:3: wall.coupling.numerator: must be a non-empty list of numbers"});
  // A bad element is named by its index and its own line.
  EXPECT_EQ(errors_of("wall:\n  coupling:\n    numerator:\n      - 0.1\n      - x\n"
                      "    denominator: [1]\n"),
            Lines{"t.yaml:5: wall.coupling.numerator[1]: must be a number, got 'x'"});
}

TEST(ConfigErrors, CouplingFeedThroughMustBeNonNegative) {
  EXPECT_EQ(errors_of("wall:\n  coupling:\n    numerator: [-0.5, 0.1]\n"
                      "    denominator: [1, -0.5]\n"),
            Lines{"t.yaml:3: wall.coupling.numerator: direct feed-through "
                  "numerator[0]/denominator[0] must be >= 0 for the contact algebraic loop to "
                  "have a unique solution, got -0.5"});
  // The sign is of the ratio: both negative is a positive feed-through.
  const Config c = load_config_text(
      "wall:\n  coupling:\n    numerator: [-0.5]\n    denominator: [-2]\n", "t.yaml");
  EXPECT_TRUE(c.wall.coupling.present);
}

// A driver's section is read by the driver's own code through the same reader: FILE:LINE
// errors, unknown keys refused, and the sections of the drivers not selected refused too.
struct FakeSettings : DriverSettings {
  double gain = 0.0;
};

DriverSchemas fake_drivers() {
  const auto read_fake = [](schema::MapReader& m,
                            const Config& cfg) -> std::shared_ptr<const DriverSettings> {
    auto s = std::make_shared<FakeSettings>();
    const auto gain = schema::read_number(m.diag(), m.take("gain"), schema::Range::greater_than(0));
    if (!gain) return nullptr;
    s->gain = *gain * cfg.device.max_force[0];  // a driver sees what was read before its section
    return s;
  };
  return {{"sim", {}}, {"fake", read_fake}, {"other", read_fake}};
}

TEST(DriverSections, TheSelectedDriverReadsItsOwnSection) {
  const Config c =
      load_config_text("device:\n  driver: fake\n  max_force: 4\n  fake:\n    gain: 2\n", "t.yaml",
                       {}, ".", fake_drivers());
  ASSERT_NE(c.device.settings, nullptr);
  EXPECT_EQ(dynamic_cast<const FakeSettings&>(*c.device.settings).gain, 8.0);
  EXPECT_EQ(c.locate("device.fake.gain"), "t.yaml:5");
}

TEST(DriverSections, ErrorsInADriversSectionNameFileAndLine) {
  const auto errors = [](std::string_view yaml) {
    try {
      load_config_text(yaml, "t.yaml", {}, ".", fake_drivers());
    } catch (const ConfigError& e) {
      return e.messages();
    }
    return Lines{};
  };
  EXPECT_EQ(errors("device:\n  driver: fake\n  fake:\n    gain: -1\n    gian: 3\n"),
            (Lines{"t.yaml:4: device.fake.gain: must be > 0, got '-1'",
                   "t.yaml:5: device.fake.gian: unknown key (did you mean 'gain'?)"}));
  EXPECT_EQ(errors("device:\n  driver: fake\n  fake: {gain: 1}\n  other: {gain: 1}\n"),
            Lines{"t.yaml:4: device.other: not used by device.driver 'fake'"});
  EXPECT_EQ(errors("device:\n  driver: usb\n"),
            Lines{"t.yaml:2: device.driver: must be one of sim, fake, other; got 'usb'"});
}

TEST(ConfigErrors, DuplicateKeysAreReported) {
  // yaml-cpp would silently use the first one; the second is almost always the intended edit.
  EXPECT_EQ(errors_of("wall:\n  stiffness: 1\n  stiffness: 2\n"),
            Lines{"t.yaml:3: wall.stiffness: duplicate key (first at line 2)"});
}

TEST(ConfigErrors, AllErrorsOfADocumentInDocumentOrder) {
  // Sections deliberately out of schema order: messages follow the file, not the schema.
  const char* yaml =
      "telemetry:\n"
      "  ring_capacity: 1\n"  // 2
      "wall:\n"
      "  stiffness: -1\n"  // 4
      "  colour: red\n"    // 5
      "loop:\n"
      "  rate_hz: 0\n"    // 7
      "  clock: fast\n";  // 8
  EXPECT_EQ(errors_of(yaml),
            (Lines{"t.yaml:2: telemetry.ring_capacity: must be in 64..4194304, got '1'",
                   "t.yaml:4: wall.stiffness: must be >= 0, got '-1'",
                   "t.yaml:5: wall.colour: unknown key; expected one of: position, normal, "
                   "stiffness, damping, discretization, delay_samples, no_pull, coupling",
                   "t.yaml:7: loop.rate_hz: must be in [1, 100000], got '0'",
                   "t.yaml:8: loop.clock: must be one of realtime, freerun; got 'fast'"}));
}

TEST(ConfigErrors, WhatJoinsTheMessagesOneALine) {
  try {
    load_config_text("wall:\n  stiffness: -1\n  damping: -1\n", "t.yaml");
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "t.yaml:2: wall.stiffness: must be >= 0, got '-1'\n"
                 "t.yaml:3: wall.damping: must be >= 0, got '-1'");
  }
}

TEST(ConfigErrors, YamlSyntaxErrorGivesLineAndColumn) {
  EXPECT_EQ(errors_of("wall:\n  stiffness: 1\n  damping: [1, 2\n"),
            Lines{"t.yaml:4:1: YAML syntax error: end of sequence flow not found"});
  EXPECT_EQ(errors_of("wall: stiffness: 1\n"),
            Lines{"t.yaml:1:16: YAML syntax error: illegal map value"});
}

}  // namespace
}  // namespace hapticd::config::testing
