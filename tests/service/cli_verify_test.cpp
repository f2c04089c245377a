#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "process.h"

namespace hapticd::testing {
namespace {

// Done-when of the loop issue: measurement and the analytic bound agree to 1e-3 for the
// backward-difference wall with 0..3 samples of delay.
TEST(CliVerify, MeasuredRequiredDampingAgreesWithTheBoundForDelays0To3) {
  for (int d = 0; d <= 3; ++d) {
    const ProcessResult r = run_process(
        {hapticd_binary(), "verify", "--json", "--set", "wall.delay_samples=" + std::to_string(d)});
    ASSERT_EQ(r.exit_code, 0) << "delay " << d << ": " << r.out << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    const double k = 2000, b = 0.2, t = 1e-3;  // config/sim.yaml; here KT >= 4B
    const double closed = d == 0 ? k * t / 2 + b : k * t / 2 * (2 * d + 1) - b * std::cos(0.0);
    EXPECT_NEAR(j["analytic_required_damping"].get<double>(), closed, 1e-9) << "delay " << d;
    EXPECT_LT(j["relative_error"].get<double>(), 1e-3) << "delay " << d;
    EXPECT_NEAR(j["measured_required_damping"].get<double>(), closed, 1e-3 * closed);
    EXPECT_EQ(j["verdict"], "agree");
  }
}

TEST(CliVerify, FindsAnInteriorWorstFrequency) {
  // One sample of delay with K T < 4 B: worst at cos(wT) = K T / (4 B) = 0.5, i.e. T/6 -> 166.7 Hz.
  const ProcessResult r =
      run_process({hapticd_binary(), "verify", "--json", "--set", "wall.stiffness=1000", "--set",
                   "wall.damping=0.5", "--set", "wall.delay_samples=1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["measured_required_damping"].get<double>(), 1.25, 1.25e-3);
  EXPECT_NEAR(j["worst_frequency_hz"].get<double>(), 1000.0 / 6, 2.0);
}

// Behind a coupling with a pole at z = 1 (H(1) = 0) the mean force of any bounded motion
// decays, so the measurement runs the linear loop the bound is about (the contact never opens)
// and waits out the coupling's slow transient.
TEST(CliVerify, MeasuresTheLinearLoopBehindACouplingWithAPoleAtOne) {
  const ProcessResult r = run_process({hapticd_binary(), "verify", "--json", "--config",
                                       source_dir() + "/config/coupling-example.yaml"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["verdict"], "agree");
  EXPECT_NEAR(j["measured_required_damping"].get<double>(), 0.1961, 1e-3);
}

// Several joints: each wall of config/sim-delta.yaml measured on the simulated delta's loop at
// the configuration the gate found worst for it agrees with the one-axis bound along its normal,
// and the gate's verdict is the measurement's: a stiff wall the device cannot hold passive there
// is measured active and refused, the box it passes is measured passive.
TEST(CliVerify, TheDeltasWallsAreMeasuredAtTheirWorstConfigurationsAndTheGateAgrees) {
  const std::string delta = source_dir() + "/config/sim-delta.yaml";
  const ProcessResult ok = run_process({hapticd_binary(), "verify", "--json", "--config", delta});
  ASSERT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  const nlohmann::json j = nlohmann::json::parse(ok.out);
  ASSERT_EQ(j["walls"].size(), 6u);
  for (const nlohmann::json& w : j["walls"]) {
    EXPECT_EQ(w["verdict"], "agree") << w.dump();
    EXPECT_TRUE(w["measured_passive"].get<bool>()) << w.dump();
    EXPECT_TRUE(w["gate_passive"].get<bool>()) << w.dump();
    // The motion met the damping the gate credits there (to the kinematics' curvature).
    EXPECT_NEAR(w["measured_normal_damping"].get<double>(), w["normal_damping"].get<double>(),
                1e-3 * w["normal_damping"].get<double>());
  }
  // One wall on the -x face at stiffness k: what `command` answers.
  const auto one_wall = [&](const char* command, int k) {
    return run_process({hapticd_binary(), command, "--json", "--config", delta, "--set",
                        "walls=[{point: [-0.02, 0, 0.11], normal: [-1, 0, 0], stiffness: " +
                            std::to_string(k) + "}]"});
  };
  const ProcessResult stiff = one_wall("verify", 1500);
  ASSERT_EQ(stiff.exit_code, 0) << stiff.out << stiff.err;
  const nlohmann::json a = nlohmann::json::parse(stiff.out)["walls"][0];
  EXPECT_FALSE(a["measured_passive"].get<bool>()) << a.dump();
  EXPECT_FALSE(a["gate_passive"].get<bool>()) << a.dump();
  EXPECT_GT(a["measured_required_damping"].get<double>(), a["normal_damping"].get<double>());
  const ProcessResult check = one_wall("check", 1500);
  EXPECT_EQ(check.exit_code, 3) << check.out;
  // Below the damping there with the margin to spare: measured passive, and passed.
  const ProcessResult soft = one_wall("verify", 900);
  ASSERT_EQ(soft.exit_code, 0) << soft.out << soft.err;
  const nlohmann::json p = nlohmann::json::parse(soft.out)["walls"][0];
  EXPECT_TRUE(p["measured_passive"].get<bool>()) << p.dump();
  EXPECT_TRUE(p["gate_passive"].get<bool>()) << p.dump();
}

}  // namespace
}  // namespace hapticd::testing
