#include <gtest/gtest.h>

#include <cmath>

#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "gate_configs.h"

namespace hapticd::gate {
namespace {

using test::demo;
using test::example1;

TEST(Gate, DemoPassesWithTheClosedFormNumbers) {
  const GateReport r = evaluate_gate(demo(), 0);
  EXPECT_TRUE(r.pass);
  EXPECT_NEAR(r.passivity.required_damping, 1.2, 1e-9);
  EXPECT_NEAR(r.passivity.available_damping, 1.8, 1e-12);
  EXPECT_NEAR(r.passivity.margin, 0.4, 1e-9);
  EXPECT_NEAR(r.passivity.worst_frequency_hz, 500.0, 1e-3);
  ASSERT_EQ(r.passivity.max_stiffness.kind, analysis::StiffnessLimit::Kind::kBounded);
  EXPECT_NEAR(r.passivity.max_stiffness.value, 3200.0, 1e-6);
  EXPECT_DOUBLE_EQ(r.static_stiffness, 2000.0);
  EXPECT_TRUE(r.oscillation.applicable);
  EXPECT_TRUE(r.reasons.empty());
}

TEST(Gate, StiffWallFailsAndNamesTheStiffnessThatPasses) {
  config::Config c = demo();
  c.wall.stiffness = 10000;
  const GateReport r = evaluate_gate(c, 0);
  EXPECT_FALSE(r.pass);
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_EQ(
      r.reasons[0],
      "passivity: required damping b_req = 5.2 N s/m exceeds (1 - safety.passivity_margin) x "
      "device.damping = (1 - 0.1) x 2 = 1.8 N s/m (worst at 500 Hz, delay 0 samples); "
      "wall.stiffness must be <= 3200 N/m to pass (now 10000), or device.damping >= 5.778 N s/m");
}

TEST(Gate, DriverDelayIsAddedToTheWallDelay) {
  config::Config c = demo();
  c.wall.stiffness = 1000;
  c.wall.delay_samples = 1;
  const GateReport r = evaluate_gate(c, 1);  // e.g. HID: one frame
  EXPECT_EQ(r.delay_samples, 2);
  // KT/2 D_2 - B cos 3u, brute-forced in the analysis tests; here only: more than one delay.
  const GateReport one = evaluate_gate(c, 0);
  EXPECT_GT(r.passivity.required_damping, one.passivity.required_damping);
  EXPECT_NEAR(one.passivity.required_damping, 0.5 + 0.2 + (1.0 - 0.4), 1e-9);  // KT >= 4B branch
}

TEST(Gate, Example1BareWallIsRefusedWithNoPassingStiffness) {
  const GateReport r = evaluate_gate(example1(false), 0);
  EXPECT_FALSE(r.pass);
  EXPECT_NEAR(r.passivity.required_damping, 30.0, 1e-9);  // KT/2 + B = 10 + 20
  EXPECT_EQ(r.passivity.max_stiffness.kind, analysis::StiffnessLimit::Kind::kNone);
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_NE(r.reasons[0].find("no wall.stiffness passes, not even 0"), std::string::npos)
      << r.reasons[0];
}

TEST(Gate, Example1CoupledWallPassesAndYieldsUnderASteadyPush) {
  const GateReport r = evaluate_gate(example1(true), 0);
  EXPECT_TRUE(r.pass) << (r.reasons.empty() ? "" : r.reasons[0]);
  EXPECT_LT(r.passivity.required_damping, 1.0);
  EXPECT_TRUE(r.coupling.present);
  EXPECT_TRUE(r.coupling.dspr);
  EXPECT_GT(r.coupling.dspr_min_real, 4.0);
  EXPECT_EQ(r.static_stiffness, 0.0);
  EXPECT_EQ(r.passivity.max_stiffness.kind, analysis::StiffnessLimit::Kind::kUnbounded);
  EXPECT_FALSE(r.oscillation.applicable);  // C's integrator: Theorem 1 covers it instead
}

TEST(Gate, UnstableCouplingFails) {
  config::Config c = example1(true);
  c.wall.coupling.denominator = {1.0, -1.5};
  c.wall.coupling.numerator = {0.1};
  const GateReport r = evaluate_gate(c, 0);
  EXPECT_FALSE(r.pass);
  bool named = false;
  for (const auto& s : r.reasons) named |= s.rfind("coupling: C(z) has a pole", 0) == 0;
  EXPECT_TRUE(named);
}

TEST(Gate, ShortageOfPassivityRaisesTheRequirement) {
  config::Config c = demo();
  c.safety.operator_passivity_shortage = 0.7;
  const GateReport r = evaluate_gate(c, 0);
  EXPECT_NEAR(r.passivity.required_damping, 1.9, 1e-9);
  EXPECT_FALSE(r.pass);  // 1.9 > 1.8
}

TEST(GateJson, HasTheDocumentedKeysAndNulls) {
  const nlohmann::json j = gate_to_json(evaluate_gate(demo(), 0));
  for (const char* k : {"sample_period_s", "delay_samples", "device_damping", "passivity",
                        "oscillation", "coupling", "verdict", "reasons"}) {
    EXPECT_TRUE(j.contains(k)) << k;
  }
  for (const char* k :
       {"required_damping", "margin", "worst_frequency_hz", "passive", "max_stiffness"})
    EXPECT_TRUE(j["passivity"].contains(k)) << k;
  for (const char* k : {"tsai_colgate", "tsypkin", "worst_frequency_hz"})
    EXPECT_TRUE(j["oscillation"].contains(k)) << k;
  for (const char* k :
       {"present", "dspr", "dspr_min_real", "transparency_gamma", "static_stiffness"})
    EXPECT_TRUE(j["coupling"].contains(k)) << k;
  EXPECT_EQ(j["verdict"], "pass");
  EXPECT_TRUE(j["coupling"]["dspr"].is_null());  // no coupling: does not apply
  EXPECT_DOUBLE_EQ(j["passivity"]["max_stiffness"].get<double>(), 3200.0);
  const nlohmann::json bare = gate_to_json(evaluate_gate(example1(false), 0));
  EXPECT_TRUE(bare["passivity"]["max_stiffness"].is_null());
  EXPECT_EQ(bare["verdict"], "fail");
}

}  // namespace
}  // namespace hapticd::gate

namespace hapticd::gate {
namespace {

// Issue 7: B/T overflowed to make b_req = -inf, and "-inf <= allowed" passed the gate. The
// configuration check refuses such numbers now, but the gate must not rely on it.
TEST(GateOverflow, ANonFiniteBoundNeverPasses) {
  config::Config c = demo();
  c.wall.damping = 1e306;
  const GateReport r = evaluate_gate(c, 0);
  EXPECT_FALSE(std::isfinite(r.passivity.required_damping));
  EXPECT_FALSE(r.passivity.passive);
  EXPECT_FALSE(r.pass);
  ASSERT_FALSE(r.reasons.empty());
  EXPECT_NE(r.reasons.front().find("passivity"), std::string::npos) << r.reasons.front();
}

}  // namespace
}  // namespace hapticd::gate
