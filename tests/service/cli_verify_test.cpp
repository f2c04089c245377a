#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

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

}  // namespace
}  // namespace hapticd::testing
