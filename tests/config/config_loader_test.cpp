// Loading text and the compiled-in default; the defaults; effective_yaml. (Reading files is
// the service's: tests/service.)
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "config_test_util.h"

namespace hapticd::config::testing {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

TEST(EmbeddedDefault, IsTheFileOnDisk) {
  const std::string on_disk = read_text(HAPTICD_SIM_YAML_PATH);
  ASSERT_FALSE(on_disk.empty()) << HAPTICD_SIM_YAML_PATH;
  EXPECT_EQ(embedded_default_yaml(), on_disk);

  const Config embedded = load_embedded_default();
  const Config file = load_config_text(on_disk, HAPTICD_SIM_YAML_PATH);
  expect_same_values(embedded, file);
  EXPECT_EQ(embedded.effective_yaml, file.effective_yaml);
  EXPECT_EQ(embedded.source_name, "config/sim.yaml (embedded)");
  EXPECT_EQ(file.source_name, HAPTICD_SIM_YAML_PATH);
}

TEST(EmbeddedDefault, IsTheHandPressDemo) {
  const Config c = load_embedded_default();
  EXPECT_EQ(c.loop.rate_hz, 1000.0);
  EXPECT_EQ(c.loop.clock, ClockMode::kRealtime);
  EXPECT_EQ(c.loop.rt_priority, 80);
  EXPECT_EQ(c.loop.cpu, -1);
  EXPECT_EQ(c.loop.overrun_fault_streak, 10);
  EXPECT_EQ(c.device.driver, "sim");
  EXPECT_EQ(c.device.settings, nullptr);
  EXPECT_EQ(c.device.mass, 0.1);
  EXPECT_EQ(c.device.damping, 2.0);
  EXPECT_EQ(c.device.max_force, 10.0);
  EXPECT_EQ(c.device.sim.counts_per_unit, 100000.0);
  EXPECT_EQ(c.device.sim.noise_counts, 0.0);
  EXPECT_EQ(c.device.sim.seed, 1u);
  EXPECT_EQ(c.device.sim.initial_position, -0.02);
  EXPECT_EQ(c.device.sim.initial_velocity, 0.0);
  EXPECT_EQ(c.device.sim.op.kind, OperatorSpec::Kind::kHand);
  EXPECT_EQ(c.device.sim.op.stiffness, 300.0);
  EXPECT_EQ(c.device.sim.op.damping, 5.0);
  EXPECT_EQ(c.device.sim.op.setpoint.shape, ProfileSpec::Shape::kPress);
  EXPECT_EQ(c.wall.position, 0.0);
  EXPECT_EQ(c.wall.normal, 1);
  EXPECT_EQ(c.wall.stiffness, 2000.0);
  EXPECT_EQ(c.wall.damping, 0.2);
  EXPECT_EQ(c.wall.discretization, Discretization::kBackward);
  EXPECT_EQ(c.wall.delay_samples, 0);
  EXPECT_FALSE(c.wall.no_pull);
  EXPECT_FALSE(c.wall.coupling.present);
  EXPECT_EQ(c.safety.gate, GateMode::kEnforce);
  EXPECT_EQ(c.safety.operator_passivity_shortage, 0.0);
  EXPECT_EQ(c.safety.passivity_margin, 0.1);
  EXPECT_EQ(c.safety.max_speed, 10.0);
  EXPECT_EQ(c.analysis.operator_stiffness, 300.0);
  EXPECT_EQ(c.analysis.operator_damping, 5.0);
  EXPECT_EQ(c.analysis.transparency_weight_numerator, Coefficients{1.0});
  EXPECT_EQ(c.analysis.transparency_weight_denominator, Coefficients{1.0});
  EXPECT_EQ(c.telemetry.log_path, "");
  EXPECT_EQ(c.telemetry.ring_capacity, 65536u);
}

TEST(EmbeddedDefault, PassesThePassivityGateWithItsMargin) {
  // Backward difference, no delay: b_req = K T/2 + B must fit in (1 - margin) b.
  const Config c = load_embedded_default();
  const double b_req = c.wall.stiffness * c.loop.sample_period_s() / 2.0 + c.wall.damping;
  EXPECT_NEAR(b_req, 1.2, 1e-12);
  EXPECT_LE(b_req, (1.0 - c.safety.passivity_margin) * c.device.damping[0]);
}

TEST(EmbeddedDefault, HandStartsAtRestOnItsSetPoint) {
  // The demo begins with no operator force: the device sits where the set-point rests.
  const Config c = load_embedded_default();
  ASSERT_FALSE(c.device.sim.op.setpoint.points.empty());
  EXPECT_EQ(c.device.sim.op.setpoint.points.front().value, c.device.sim.initial_position);
}

TEST(Defaults, EmptyDocumentGivesTheDefaultsOfConfigH) {
  const Config expected;
  for (const char* text : {"", "# nothing but a comment\n", "---\n"}) {
    const Config c = load_config_text(text, "empty.yaml");
    expect_same_values(c, expected);
    EXPECT_EQ(c.source_name, "empty.yaml");
    EXPECT_EQ(c.effective_yaml, "{}\n");
  }
  // The same with every section present but empty.
  expect_same_values(
      load_config_text("loop:\ndevice:\n  sim:\nwall:\nsafety:\nanalysis:\ntelemetry:\n", "t"),
      expected);
}

TEST(Defaults, CommentedOutCouplingMeansNoCoupling) {
  const Config c = load_config_text("wall:\n  coupling:\n  #  numerator: [1]\n", "t.yaml");
  EXPECT_FALSE(c.wall.coupling.present);
}

TEST(Defaults, AbsentTransparencyWeightIsOne) {
  const Config c = load_config_text("analysis:\n  operator: {stiffness: 400}\n", "t.yaml");
  EXPECT_EQ(c.analysis.operator_stiffness, 400.0);
  EXPECT_EQ(c.analysis.operator_damping, 5.0);
  EXPECT_EQ(c.analysis.transparency_weight_numerator, Coefficients{1.0});
  EXPECT_EQ(c.analysis.transparency_weight_denominator, Coefficients{1.0});
}

TEST(Values, NumbersBooleansAndIntegersInTheirYamlForms) {
  const Config c = load_config_text(
      "loop:\n  rate_hz: 2.5e3\n  rt_priority: +50\n"
      "wall:\n  no_pull: yes\n  normal: -1\n  stiffness: \"1500\"\n"
      "device:\n  sim:\n    seed: 12345678901\n",
      "t.yaml");
  EXPECT_EQ(c.loop.rate_hz, 2500.0);
  EXPECT_EQ(c.loop.rt_priority, 50);
  EXPECT_TRUE(c.wall.no_pull);
  EXPECT_EQ(c.wall.normal, -1);
  EXPECT_EQ(c.wall.stiffness, 1500.0);
  EXPECT_EQ(c.device.sim.seed, 12345678901u);
  EXPECT_FALSE(load_config_text("wall:\n  no_pull: off\n", "t").wall.no_pull);
}

TEST(Values, CouplingAndWeightLists) {
  const Config c = load_config_text(
      "wall:\n  coupling:\n    numerator: [0.1, -0.0752, 0.0016, -0.0101]\n"
      "    denominator: [1, -1.8407, 0.8444, -0.0037]\n"
      "analysis:\n  transparency_weight:\n    numerator: [0.5, 0.5]\n    denominator: [1]\n",
      "t.yaml");
  ASSERT_TRUE(c.wall.coupling.present);
  EXPECT_EQ(c.wall.coupling.numerator, (Coefficients{0.1, -0.0752, 0.0016, -0.0101}));
  EXPECT_EQ(c.wall.coupling.denominator, (Coefficients{1, -1.8407, 0.8444, -0.0037}));
  EXPECT_EQ(c.analysis.transparency_weight_numerator, (Coefficients{0.5, 0.5}));
}

TEST(EffectiveYaml, ReloadsToTheSameConfiguration) {
  const Config first = load_embedded_default(sets({"wall.stiffness=2500", "wall.no_pull=true"}));
  const Config again = load_config_text(first.effective_yaml, "log header");
  expect_same_values(first, again);
  EXPECT_EQ(again.effective_yaml, first.effective_yaml);
}

TEST(EffectiveYaml, ShowsTheMergedDocumentAfterSet) {
  const Config c = load_config_text("wall:\n  stiffness: 1000  # a comment\n", "t.yaml",
                                    sets({"wall.stiffness=2500", "loop.rate_hz=2000"}));
  EXPECT_EQ(c.effective_yaml, "wall:\n  stiffness: 2500\nloop:\n  rate_hz: 2000\n");
}

}  // namespace
}  // namespace hapticd::config::testing
