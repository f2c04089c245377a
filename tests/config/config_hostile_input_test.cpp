// Inputs a hostile or careless user gives the loader (issue 7): each must be refused with a
// message that names the place, never silently read as something else.
#include <gtest/gtest.h>

#include <string>

#include "config/config_loader.h"
#include "config_test_util.h"

namespace hapticd::config::testing {
namespace {

TEST(HostileConfig, ASecondDocumentIsRefusedNotIgnored) {
  EXPECT_EQ(errors_of("wall:\n  stiffness: 100\n---\nwall:\n  stiffness: 1e9\n"),
            Lines{"t.yaml:4: a second YAML document ('---') follows the first; a configuration "
                  "is one document"});
  EXPECT_EQ(errors_of("wall:\n  stiffness: 100\n", sets({"wall.stiffness=1\n---\n2"})),
            Lines{"--set wall.stiffness=1\\x0a---\\x0a2: wall.stiffness: value holds more than "
                  "one YAML document ('---')"});
}

// yaml-cpp 0.7's LoadAll never returns on a stray ',' and allocates until memory runs out
// (found by fuzz/, regressions new-yaml-loadall-comma-*): refused with the place instead.
TEST(HostileConfig, AStrayCommaIsASyntaxErrorNotAHang) {
  EXPECT_EQ(errors_of(",\n"),
            Lines{"t.yaml:1:1: YAML syntax error: unexpected ',': the YAML parser cannot get "
                  "past it"});
  EXPECT_EQ(errors_of("", sets({"wall.stiffness=,"})),
            Lines{"--set wall.stiffness=,: wall.stiffness: value is not valid YAML: unexpected "
                  "',': the YAML parser cannot get past it"});
}

TEST(HostileConfig, ANumberBelowTheDoubleRangeIsRefusedNotZero) {
  EXPECT_EQ(errors_of("wall:\n  damping: 1e-400\n"),
            Lines{"t.yaml:2: wall.damping: is too close to zero to be represented (it would "
                  "become 0), got '1e-400'"});
  EXPECT_EQ(errors_of("wall:\n  position: -2e-400\n"),
            Lines{"t.yaml:2: wall.position: is too close to zero to be represented (it would "
                  "become 0), got '-2e-400'"});
  // A subnormal is still a number, and is kept as such.
  EXPECT_EQ(load_config_text("wall:\n  position: -2e-320\n", "t.yaml").wall.position, -2e-320);
  EXPECT_EQ(load_config_text("wall:\n  damping: 0e-400\n", "t.yaml").wall.damping, 0.0);
}

TEST(HostileConfig, ControlBytesAreEscapedInMessages) {
  const Lines e = errors_of("wall:\n  discretization: \"\\e[2J\\e[31mfine\\r\"\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0],
            "t.yaml:2: wall.discretization: must be one of backward, tustin; got "
            "'\\x1b[2J\\x1b[31mfine\\x0d'");
  for (const std::string& m : errors_of("\"k\\x07\\x7f\": 1\n")) {
    for (char c : m) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << m;
  }
}

// 40k unknown keys used to take seconds (a linear duplicate search per key) and printed every
// one of them: the messages stop at a readable number and say how many more there are.
TEST(HostileConfig, ThousandsOfKeysGiveABoundedReport) {
  std::string yaml = "wall:\n";
  for (int i = 0; i < 40000; ++i) yaml += "  k" + std::to_string(i) + ": 1\n";
  yaml += "  k7: 2\n";  // a duplicate among them is still found
  const Lines e = errors_of(yaml);
  ASSERT_EQ(e.size(), kMaxMessages + 1);
  EXPECT_EQ(e.back(), "t.yaml: ... and 39901 more problems not shown");
  EXPECT_EQ(e.front(),
            "t.yaml:2: wall.k0: unknown key; expected one of: position, normal, "
            "stiffness, damping, discretization, delay_samples, no_pull, coupling");
}

TEST(HostileConfig, KeyLocationsNameTheLineOrTheSetArgument) {
  const Config c = load_config_text("wall:\n  stiffness: 100\n  damping: 0.1\n", "t.yaml",
                                    sets({"wall.damping=0.3", "loop.rate_hz=500"}));
  EXPECT_EQ(c.locate("wall.stiffness"), "t.yaml:2");
  EXPECT_EQ(c.locate("wall.damping"), "--set wall.damping=0.3");
  EXPECT_EQ(c.locate("loop.rate_hz"), "--set loop.rate_hz=500");
  EXPECT_EQ(c.locate("wall.coupling"), "t.yaml:1");  // absent: the enclosing key
  EXPECT_EQ(c.locate("telemetry.log"), "t.yaml");    // a default: the file
}

}  // namespace
}  // namespace hapticd::config::testing
