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

// A delta's box of walls, each proven along its normal over the workspace: `check` says where
// each wall is weakest and how stiff it may be, refuses a wall too stiff for the device's
// damping there by name, and a run whose device drives another number of joints than
// device.kinematics describes never enables output. (A delta has `walls`, not the one joint's
// `wall`, which the embedded file sets: null switches it off.)
std::string delta_yaml() { return source_dir() + "/config/sim-delta.yaml"; }

TEST(CliCheck, ADeltasBoxIsProvenWallByWallOverItsWorkspace) {
  const std::string box =
      "--set=walls=[{point: [0.03, 0, 0.11], normal: [1, 0, 0], stiffness: 500}, "
      "{point: [0, 0, 0.08], normal: [0, 0, -1], stiffness: STIFF}]";
  auto check = [&](const std::string& stiff, bool json) {
    std::string b = box;
    b.replace(b.find("STIFF"), 5, stiff);
    std::vector<std::string> args{hapticd_binary(),      "check", "--config", delta_yaml(), "--set",
                                  "device.damping=0.05", b};
    if (json) args.push_back("--json");
    return run_process(args);
  };
  const ProcessResult ok = check("500", true);
  EXPECT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  const nlohmann::json j = nlohmann::json::parse(ok.out);
  ASSERT_EQ(j["workspace"]["walls"].size(), 2u);
  EXPECT_GT(j["workspace"]["walls"][0]["normal_damping"].get<double>(), 1.0);
  EXPECT_EQ(j["workspace"]["samples"], 17 * 17 * 17);

  const ProcessResult stiff = check("60000", false);
  EXPECT_EQ(stiff.exit_code, 3) << stiff.out << stiff.err;
  EXPECT_NE(stiff.out.find("fail: walls[1]: b_req 30 exceeds"), std::string::npos) << stiff.out;
  EXPECT_NE(stiff.out.find("walls[1].stiffness must be <= "), std::string::npos) << stiff.out;
  EXPECT_EQ(stiff.out.find("design-coupling"), std::string::npos) << stiff.out;

  // safety.gate: derate lowers the failing wall to its own largest passing K (the report's),
  // runs it, says so in the summary and the log, and records it in the tick log's document:
  // the replay rebuilds the walls that ran.
  const double k_max = [&] {
    const ProcessResult out = check("60000", true);
    return nlohmann::json::parse(out.out)["workspace"]["walls"][1]["max_stiffness"].get<double>();
  }();
  std::string b = box;
  b.replace(b.find("STIFF"), 5, "60000");
  const std::string sum = temp_path("derated-walls.json"), log = temp_path("derated-walls.hlog");
  const ProcessResult derate =
      run_process({hapticd_binary(), "run", "--duration", "1", "--config", delta_yaml(), "--set",
                   "device.damping=0.05", "--set", "safety.gate=derate", "--set",
                   "loop.clock=freerun", b, "--summary-json", sum, "--log", log});
  EXPECT_EQ(derate.exit_code, 0) << derate.out << derate.err;
  const nlohmann::json s = nlohmann::json::parse(read_file(sum));
  EXPECT_TRUE(s["derated"].is_null());
  ASSERT_EQ(s["derated_walls"].size(), 1u) << s["derated_walls"];
  EXPECT_EQ(s["derated_walls"][0]["key"], "walls[1].stiffness");
  EXPECT_EQ(s["derated_walls"][0]["wall"], 1);
  EXPECT_EQ(s["derated_walls"][0]["configured"].get<double>(), 60000.0);
  EXPECT_EQ(s["derated_walls"][0]["ran"].get<double>(), k_max);
  EXPECT_EQ(s["gate"]["verdict"], "pass");
  EXPECT_NE(derate.out.find("DERATED       walls[1].stiffness 60000 N/m configured"),
            std::string::npos)
      << derate.out;
  const ProcessResult replay = run_process({hapticd_binary(), "replay", log, "--json"});
  EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  EXPECT_EQ(nlohmann::json::parse(replay.out)["reproduced"]["differing"], 0) << replay.out;
}

// The example configuration of several joints passes its gate, and the direction check, which
// pushes one joint, is refused by name for several rather than skipped.
TEST(CliCheck, TheDeltaExamplePassesAndADirectionCheckOnSeveralJointsIsRefused) {
  const ProcessResult ok = run_process({hapticd_binary(), "check", "--config", delta_yaml()});
  EXPECT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  const ProcessResult r =
      run_process({hapticd_binary(), "run", "--duration", "1", "--config", delta_yaml(), "--set",
                   "safety.direction_check.mode=enforce"});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("safety.direction_check: the direction check pushes one joint; a device "
                       "of 3 joints runs with `mode: off`"),
            std::string::npos)
      << r.err;
  // The one joint's start and the operators that move one joint have no meaning here.
  const ProcessResult start = run_process({hapticd_binary(), "check", "--config", delta_yaml(),
                                           "--set", "device.sim.initial_position=0.01"});
  EXPECT_EQ(start.exit_code, 2);
  EXPECT_NE(start.err.find("device.sim.initial_position"), std::string::npos) << start.err;
  const ProcessResult origin = run_process({hapticd_binary(), "check", "--config", delta_yaml(),
                                            "--set", "device.sim.operator.origin=[0, 0, 0.5]"});
  EXPECT_EQ(origin.exit_code, 2);
  EXPECT_NE(origin.err.find("device.sim.operator.origin: is not a pose of the mechanism"),
            std::string::npos)
      << origin.err;
}

// What measures or designs for one joint's wall refuses several joints by name rather than
// answering about a wall the configuration does not have.
TEST(CliCheck, OneJointCommandsRefuseSeveralJointsByName) {
  for (const char* command : {"curves", "design-coupling"}) {
    const ProcessResult r = run_process({hapticd_binary(), command, "--config", delta_yaml()});
    EXPECT_EQ(r.exit_code, 2) << command << r.out << r.err;
    EXPECT_NE(r.err.find(std::string("device.kinematics: `hapticd ") + command +
                         "` works on the wall of one joint; kind delta has 3"),
              std::string::npos)
        << command << ": " << r.err;
  }
  // identify excites one joint of several: it must be told which.
  const ProcessResult r = run_process({hapticd_binary(), "identify", "--config", delta_yaml()});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--joint: device.kinematics (kind delta) has 3 joints: say which one to "
                       "excite (0 to 2; the others are commanded zero)"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace hapticd::testing
