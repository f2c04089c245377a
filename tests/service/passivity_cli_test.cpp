// The runtime passivity observer and controller, and safety.gate: derate, as a user meets
// them: `hapticd run` on the sim, its summary, its tick log and `hapticd replay` of it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

struct LoggedRun {
  ProcessResult process;
  json summary;
  std::vector<telemetry::TickRecord> records;
};

LoggedRun run_logged(const std::string& name, std::vector<std::string> args) {
  const std::string log = temp_path(name + ".hlog"), sum = temp_path(name + ".json");
  args.insert(args.begin(), {hapticd_binary(), "run", "--log", log, "--summary-json", sum});
  LoggedRun r{run_process(args), {}, {}};
  if (r.process.exit_code == 0) {
    r.summary = json::parse(read_file(sum));
    r.records = telemetry::read_log(log).records;
  }
  return r;
}

double max_speed_in_last(const std::vector<telemetry::TickRecord>& r, std::size_t n) {
  double v = 0.0;
  for (std::size_t k = r.size() - n; k < r.size(); ++k) v = std::max(v, std::abs(r[k].velocity));
  return v;
}

TEST(CliPassivity, AGatePassingWallKeepsTheObservedEnergyNonNegative) {
  // The embedded demo: a hand presses into a wall the gate passes, with encoder quantisation.
  const LoggedRun r =
      run_logged("observe_pass", {"--duration", "5", "--set", "loop.clock=freerun"});
  ASSERT_EQ(r.process.exit_code, 0) << r.process.err;
  const json& p = r.summary["passivity"];
  EXPECT_EQ(p["mode"], "observe");
  EXPECT_GE(p["min_energy_j"].get<double>(), 0.0);
  EXPECT_EQ(p["negative_ticks"], 0);
  EXPECT_GT(r.summary["counters"]["loop"]["contact_ticks"].get<int>(), 1000);  // it really pressed
  ASSERT_EQ(r.records.size(), 5000u);
  for (const auto& rec : r.records) ASSERT_GE(rec.observer_energy_j, 0.0) << rec.tick;
  EXPECT_EQ(r.records.back().observer_energy_j, p["energy_j"].get<double>());
  EXPECT_NE(r.process.out.find("0 ticks below zero"), std::string::npos) << r.process.out;
}

TEST(CliPassivity, AWallTheGateRefusesGoesNegativeAndDampStopsItPumpingEnergyIntoTheHand) {
  // Naghshtabrizi and Hespanha's Example 1 without its coupling, forced on with warn: it
  // falls into a Nyquist-rate bounce that hands the hand energy.
  const std::vector<std::string> bare = {
      "--config", coupling_example(), "--duration", "20",
      "--set",    "wall.coupling=",   "--set",      "safety.gate=warn"};
  auto with = [&](const std::string& mode) {
    std::vector<std::string> a = bare;
    a.insert(a.end(), {"--set", "safety.passivity_controller=" + mode});
    return a;
  };
  const LoggedRun observed = run_logged("bare_observe", with("observe"));
  const LoggedRun damped = run_logged("bare_damp", with("damp"));
  ASSERT_EQ(observed.process.exit_code, 0) << observed.process.err;
  ASSERT_EQ(damped.process.exit_code, 0) << damped.process.err;
  const json &o = observed.summary["passivity"], &d = damped.summary["passivity"];
  EXPECT_LT(o["min_energy_j"].get<double>(), -10.0) << o.dump();
  EXPECT_GT(o["negative_ticks"].get<int>(), 900);
  EXPECT_NE(observed.process.out.find("THE LOOP PUT ENERGY INTO THE HAND"), std::string::npos);
  EXPECT_LT(observed.summary["operator_work_j"].get<double>(), -10.0);  // the hand got it
  EXPECT_GT(max_speed_in_last(observed.records, 250), 0.3);

  // With the controller the energy stops growing and the hand is no longer pumped.
  EXPECT_GT(damped.summary["passivity"]["min_energy_j"].get<double>(), -1.0) << d.dump();
  EXPECT_GT(d["damped_ticks"].get<int>(), 0);
  EXPECT_LE(d["max_damping"].get<double>(), 0.9 * 2.0 * 0.1 / 0.02 + 1e-12);
  EXPECT_GT(damped.summary["operator_work_j"].get<double>(), -0.1);
  EXPECT_LT(max_speed_in_last(damped.records, 250), 0.1 * max_speed_in_last(observed.records, 250));
  const auto damped_ticks =
      std::count_if(damped.records.begin(), damped.records.end(), [](auto& r) {
        return (r.flags & telemetry::kFlagPassivityDamped) != 0 && r.passivity_damping > 0.0;
      });
  EXPECT_EQ(damped_ticks, d["damped_ticks"].get<int>());
}

TEST(CliPassivity, TheControllersOwnForcesNeverPutEnergyInWhateverTheHandDoes) {
  // The bare wall again, pressed by a hand whose set-point shakes at 2 Hz, 8 Hz (tremor) and
  // 12 Hz (four samples a cycle at this 50 Hz loop, where a guess of the coming velocity is
  // always wrong): the governor keeps the controller's own work in the device at most one
  // step's worth, and the wall with the controller never ends with less energy than without.
  for (const char* hz : {"2", "8", "12"}) {
    const std::string shake = std::string("device.sim.operator.setpoint={shape: sine, ") +
                              "offset: 0.005, amplitude: 0.01, frequency_hz: " + hz + "}";
    json summary[2];
    for (int damp = 0; damp < 2; ++damp) {
      const std::string sum = temp_path(std::string("shake_") + hz + ".json");
      const ProcessResult r = run_process(
          {hapticd_binary(), "run", "--config", coupling_example(), "--duration", "20",
           "--summary-json", sum, "--set", "wall.coupling=", "--set", "safety.gate=warn", "--set",
           shake, "--set",
           damp ? "safety.passivity_controller=damp" : "safety.passivity_controller=observe"});
      ASSERT_EQ(r.exit_code, 0) << r.err;
      summary[damp] = json::parse(read_file(sum))["passivity"];
    }
    EXPECT_GT(summary[1]["damping_work_j"].get<double>(), -0.05) << hz << " Hz";
    EXPECT_GT(summary[1]["energy_j"].get<double>(), summary[0]["energy_j"].get<double>() - 1.0)
        << hz << " Hz: " << summary[0].dump() << " " << summary[1].dump();
  }
}

// `hapticd run` with `args` and the controller damping, then `hapticd replay --json` of its log.
json run_and_replay(const std::string& name, std::vector<std::string> args) {
  const std::string log = temp_path(name + ".hlog");
  args.insert(args.begin(), {hapticd_binary(), "run", "--log", log});
  args.insert(args.end(),
              {"--set", "safety.gate=warn", "--set", "safety.passivity_controller=damp"});
  EXPECT_EQ(run_process(args).exit_code, 0);
  const ProcessResult r = run_process({hapticd_binary(), "replay", log, "--json"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  return json::parse(r.out);
}

TEST(CliPassivity, ReplayReproducesTheObserverAtARateWithoutWholeNanoseconds) {
  // 1024 Hz: 976562.5 ns, which the loop runs as 976563; replay must use the same T.
  const json j = run_and_replay("r1024", {"--duration", "3", "--set", "loop.clock=freerun", "--set",
                                          "loop.rate_hz=1024", "--set", "wall.stiffness=20000"});
  EXPECT_EQ(j["reproduced"]["differing"], 0);
  EXPECT_GT(j["logged"]["damped_ticks"].get<int>(), 0);
}

TEST(CliPassivity, ReplayReproducesTheControllersForcesBitForBit) {
  const json j = run_and_replay("damp_replay", {"--config", coupling_example(), "--duration", "5",
                                                "--set", "wall.coupling="});
  EXPECT_EQ(j["reproduced"]["differing"], 0);
  EXPECT_EQ(j["reproduced"]["identical"], true);
  EXPECT_GT(j["logged"]["damped_ticks"].get<int>(), 0);
  EXPECT_EQ(j["logged"]["damped_ticks"], j["replayed"]["damped_ticks"]);
  EXPECT_EQ(j["logged"]["min_observer_energy_j"], j["replayed"]["min_observer_energy_j"]);
}

TEST(CliPassivity, DerateRunsTheLargestPassingStiffnessAndSaysSo) {
  const ProcessResult check =
      run_process({hapticd_binary(), "check", "--json", "--set", "wall.stiffness=20000"});
  ASSERT_EQ(check.exit_code, 3);
  const double k_max = json::parse(check.out)["passivity"]["max_stiffness"].get<double>();
  const std::string log = temp_path("derated.hlog");
  const LoggedRun r =
      run_logged("derated", {"--duration", "2", "--set", "loop.clock=freerun", "--set",
                             "wall.stiffness=20000", "--set", "safety.gate=derate"});
  ASSERT_EQ(r.process.exit_code, 0) << r.process.err;
  EXPECT_EQ(r.summary["derated"]["configured"].get<double>(), 20000.0);
  EXPECT_EQ(r.summary["derated"]["ran"].get<double>(), k_max);
  const ProcessResult told = run_process({hapticd_binary(), "check", "--json", "--set",
                                          "wall.stiffness=20000", "--set", "safety.gate=derate"});
  EXPECT_EQ(told.exit_code, 3) << "check judges the configured wall";
  EXPECT_EQ(json::parse(told.out)["derated"]["ran"].get<double>(), k_max);
  EXPECT_EQ(r.summary["gate"]["verdict"], "pass");
  EXPECT_NE(r.process.out.find("DERATED"), std::string::npos) << r.process.out;
  EXPECT_NE(r.process.err.find("DERATED"), std::string::npos) << r.process.err;
  EXPECT_GE(r.summary["passivity"]["min_energy_j"].get<double>(), 0.0);
  // The log records the law that ran: its replay reproduces the forces.
  const ProcessResult replay =
      run_process({hapticd_binary(), "replay", temp_path("derated.hlog"), "--json"});
  EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
}

TEST(CliPassivity, DerateRefusesWhenNoStiffnessPasses) {
  // B alone needs more than the device's b: no K makes the wall passive.
  const ProcessResult r =
      run_process({hapticd_binary(), "run", "--duration", "1", "--set", "loop.clock=freerun",
                   "--set", "wall.damping=5", "--set", "safety.gate=derate"});
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
}

TEST(CliPassivity, OffRecordsNoEnergyAndSaysSo) {
  const LoggedRun r = run_logged("observer_off", {"--duration", "1", "--set", "loop.clock=freerun",
                                                  "--set", "safety.passivity_controller=off"});
  ASSERT_EQ(r.process.exit_code, 0) << r.process.err;
  EXPECT_EQ(r.summary["passivity"], json({{"mode", "off"}}));
  for (const auto& rec : r.records) ASSERT_EQ(rec.observer_energy_j, 0.0);
  EXPECT_NE(r.process.out.find("observer off"), std::string::npos);
}

TEST(CliPassivity, BadSettingsAreRefusedWithTheKeyNamed) {
  ProcessResult r =
      run_process({hapticd_binary(), "check", "--set", "safety.passivity_controller=sometimes"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("safety.passivity_controller: must be one of off, observe, damp"),
            std::string::npos)
      << r.err;
  r = run_process({hapticd_binary(), "check", "--set", "safety.passivity_max_damping=0"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("safety.passivity_max_damping"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace hapticd::testing
