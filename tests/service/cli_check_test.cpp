#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "process.h"

namespace hapticd::testing {
namespace {

std::string sim_yaml() { return source_dir() + "/config/sim.yaml"; }

TEST(CliCheck, SimYamlPasses) {
  const ProcessResult r = run_process({hapticd_binary(), "check", "--config", sim_yaml()});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("required damping b_req    1.2 N s/m at 500 Hz"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("verdict                     PASS"), std::string::npos) << r.out;
}

TEST(CliCheck, StiffWallFailsWithExit3AndNamesThePassingStiffness) {
  const ProcessResult r = run_process(
      {hapticd_binary(), "check", "--config", sim_yaml(), "--set", "wall.stiffness=10000"});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.out.find("wall.stiffness must be <= 3200 N/m to pass (now 10000)"), std::string::npos)
      << r.out;
}

TEST(CliCheck, JsonIsExactlyOneObjectWithTheDocumentedKeys) {
  const ProcessResult r =
      run_process({hapticd_binary(), "check", "--json", "--set", "wall.delay_samples=1"});
  EXPECT_EQ(r.exit_code, 3) << r.err;  // one sample of delay: b_req 2.8 > 1.8 allowed
  const nlohmann::json j = nlohmann::json::parse(r.out);  // throws on anything but one value
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["delay_samples"], 1);
  EXPECT_DOUBLE_EQ(j["sample_period_s"].get<double>(), 1e-3);
  EXPECT_DOUBLE_EQ(j["device_damping"].get<double>(), 2.0);
  EXPECT_NEAR(j["passivity"]["required_damping"].get<double>(), 1.0 + 0.2 + (2.0 - 0.4), 1e-9);
  EXPECT_TRUE(j["passivity"]["passive"].is_boolean());
  EXPECT_TRUE(j["passivity"]["max_stiffness"].is_number());
  EXPECT_TRUE(j["oscillation"]["tsai_colgate"].is_boolean());
  EXPECT_TRUE(j["coupling"]["dspr"].is_null());
  EXPECT_EQ(j["verdict"], "fail");  // 2.8 > 1.8
  EXPECT_EQ(j["reasons"].size(), 1u);
}

TEST(CliCheck, BadConfigurationExits2WithFileLineAndKey) {
  const std::string path = temp_path("bad.yaml");
  std::ofstream(path) << "wall:\n  stiffness: -5\n  dampnig: 1\n";
  const ProcessResult r = run_process({hapticd_binary(), "check", "--config", path});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "hapticd: " + path + ":2: wall.stiffness: must be >= 0, got '-5'\n" +
                       "hapticd: " + path +
                       ":3: wall.dampnig: unknown key (did you mean 'damping'?)\n");
}

TEST(CliCheck, BadSetAndMissingFileExit2) {
  EXPECT_EQ(run_process({hapticd_binary(), "check", "--set", "wall.stiffness=abc"}).err,
            "hapticd: --set wall.stiffness=abc: wall.stiffness: must be a number, got 'abc'\n");
  const ProcessResult r = run_process({hapticd_binary(), "check", "--config", "/nonexistent.yaml"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "hapticd: /nonexistent.yaml: cannot read: No such file or directory\n");
}

TEST(CliCheck, ReportsTheDriverAndTheDelayItDeclares) {
  const ProcessResult r =
      run_process({hapticd_binary(), "check", "--json", "--set", "wall.delay_samples=2"});
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["driver"], "sim");
  EXPECT_EQ(j["device_delay_samples"], 0);  // in-process
  EXPECT_EQ(j["wall_delay_samples"], 2);
  EXPECT_EQ(j["delay_samples"], 2);
}

TEST(CliHelp, EverySubcommandDocumentsItsOptions) {
  const std::pair<const char*, std::vector<const char*>> expected[] = {
      {"check", {"--config", "--set", "--json", "Exit 0 pass, 3 fail, 2 bad input"}},
      {"run", {"--config", "--set", "--duration", "--log", "--summary-json", "SIGTERM"}},
      {"verify", {"--config", "--set", "--json", "Nyquist"}}};
  for (const auto& [cmd, words] : expected) {
    const ProcessResult r = run_process({hapticd_binary(), cmd, "--help"});
    EXPECT_EQ(r.exit_code, 0) << cmd;
    for (const char* w : words)
      EXPECT_NE(r.out.find(w), std::string::npos) << cmd << " --help lacks " << w;
  }
  EXPECT_EQ(run_process({hapticd_binary()}).exit_code, 2);  // no sub-command: usage error
  EXPECT_EQ(run_process({hapticd_binary(), "run", "--duration", "-1"}).exit_code, 2);
}

// Several joints are read and checked but not yet proven: the gate refuses them by name (and
// says no coupling will help), and a run whose device drives another number of joints than
// device.kinematics describes never enables output, even with the gate only warning. (A delta
// has `walls`, not the one joint's `wall`, which the embedded file sets: null switches it off.)
TEST(CliCheck, SeveralJointsAreRefusedUntilTheGateProvesAWorkspace) {
  const ProcessResult c =
      run_process({hapticd_binary(), "check", "--set", "device.kinematics.kind=delta", "--set",
                   "wall=null"});
  EXPECT_EQ(c.exit_code, 3) << c.out << c.err;
  EXPECT_NE(c.out.find("fail: device.kinematics: kind delta drives 3 joints"), std::string::npos)
      << c.out;
  EXPECT_EQ(c.out.find("design-coupling"), std::string::npos) << c.out;

  const ProcessResult r =
      run_process({hapticd_binary(), "run", "--duration", "1", "--set",
                   "device.kinematics.kind=delta", "--set", "wall=null", "--set",
                   "safety.gate=warn"});
  EXPECT_EQ(r.exit_code, 4) << r.out << r.err;
  EXPECT_NE(r.err.find("sim: the device drives 1 joint(s) but device.kinematics (delta) has 3"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace hapticd::testing
