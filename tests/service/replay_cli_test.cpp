// `hapticd replay` on logs of real runs: the log's own configuration reproduces its forces bit
// for bit - freerun and realtime, behind a coupling and two samples of delay, across a live
// reload, a re-arming after a cleared fault and rotated segments - a tampered force is caught,
// and another configuration gets its gate verdict, a side-by-side summary and its own series.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "daemon.h"
#include "process.h"
#include "telemetry/log_reader.h"
#include "telemetry/log_writer.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

// A damped wall behind a coupling and two samples of delay: every history a replay must rebuild.
const std::vector<std::string> kCoupledDelayed = {
    "--set", "wall.delay_samples=2", "--set",
    "wall.coupling={numerator: [0.001], denominator: [1]}"};

json replay_json(const std::string& log, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{hapticd_binary(), "replay", log, "--json"};
  args.insert(args.end(), extra.begin(), extra.end());
  const ProcessResult r = run_process(args);
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 3) << r.err;
  return json::parse(r.out, nullptr, false);
}

void expect_reproduced(const json& j, std::size_t ticks) {
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["reproduced"]["identical"], true) << j.dump(2);
  EXPECT_EQ(j["reproduced"]["differing"], 0) << j.dump(2);
  EXPECT_EQ(j["ticks"], ticks);
  EXPECT_TRUE(j["stopped"].is_null()) << j["stopped"];
}

TEST(CliReplay, AFreerunLogIsReproducedBitForBitAndItsEnergyAgrees) {
  const std::string log = temp_path("replay_free.hlog"), sum = temp_path("replay_free.json");
  std::vector<std::string> args{
      hapticd_binary(),    "run", "--duration", "3", "--log", log, "--summary-json", sum, "--set",
      "loop.clock=freerun"};
  args.insert(args.end(), kCoupledDelayed.begin(), kCoupledDelayed.end());
  ASSERT_EQ(run_process(args).exit_code, 0);
  const json j = replay_json(log);
  expect_reproduced(j, 3000);
  // Every tick: the law's, and the direction check's pulse replayed from its positions.
  EXPECT_EQ(j["reproduced"]["compared"], 3000);
  const json s = json::parse(read_file(sum));
  EXPECT_GT(s["direction_check"]["ticks"].get<int>(), 100);
  // The same sum over the same numbers in the same order as the loop's own count.
  EXPECT_EQ(j["logged"]["wall_energy_j"].get<double>(), s["wall_energy_j"].get<double>());
  EXPECT_EQ(j["replayed"]["wall_energy_j"].get<double>(), s["wall_energy_j"].get<double>());
  EXPECT_EQ(j["logged"]["contact_ticks"], s["counters"]["loop"]["contact_ticks"]);
  // The log ends with the run's counters, the same the summary shows.
  EXPECT_EQ(j["counters"], s["counters"]);
  EXPECT_EQ(j["anomalies"], s["anomalies"]);
  const ProcessResult text = run_process({hapticd_binary(), "replay", log});
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_TRUE(has(text.out, "reproduced bit for bit by the log's own configuration")) << text.out;
}

TEST(CliReplay, ARealtimeLogWithALiveReloadIsReproducedAcrossTheSwap) {
  const std::string yaml = pressing_config(2000, "",
                                           "  delay_samples: 2\n"
                                           "  coupling: {numerator: [0.001], denominator: [1]}\n");
  const std::string base = temp_path("replay_base.yaml"), next = temp_path("replay_next.yaml");
  std::ofstream(base) << yaml;
  std::string changed = yaml;
  changed.replace(changed.find("stiffness: 2000"), 15, "stiffness: 1500");
  std::ofstream(next) << changed;
  Daemon d({"--config", base, "--duration", "120"});
  ASSERT_TRUE(d.ready());
  d.wait_status(
      [](const json& s) { return s["counters"]["loop"]["contact_ticks"].get<int>() > 200; });
  ASSERT_EQ(d.ctl({"reload", next}).exit_code, 0);
  d.wait_status(
      [](const json& s) { return s["counters"]["loop"]["contact_ticks"].get<int>() > 500; });
  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  ASSERT_EQ(d.wait().exit_code, 0);
  const json s = json::parse(read_file(d.summary()));
  const json j = replay_json(d.log());
  expect_reproduced(j, s["ticks"].get<std::size_t>());
  EXPECT_EQ(j["reloads"], 1);
  EXPECT_EQ(j["logged"]["wall_energy_j"].get<double>(), s["wall_energy_j"].get<double>());
}

TEST(CliReplay, ALogThatReArmedAfterAClearedFaultIsReproduced) {
  Daemon d({"--on-fault", "hold", "--duration", "120", "--set", "device.sim.initial_velocity=0.6",
            "--set", "safety.max_speed=0.3", "--set", "device.sim.operator.damping=50", "--set",
            "safety.direction_check.on_no_motion=run"});  // the hand holds it firmly
  ASSERT_TRUE(d.ready());
  d.wait_status([](const json& s) { return s["state"] == "faulted"; });
  ASSERT_EQ(d.ctl({"clear-fault"}).exit_code, 0);
  d.wait_status(
      [](const json& s) { return s["counters"]["loop"]["contact_ticks"].get<int>() > 200; });
  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  ASSERT_EQ(d.wait().exit_code, 0);
  const json j = replay_json(d.log());
  expect_reproduced(j, json::parse(read_file(d.summary()))["ticks"].get<std::size_t>());
  EXPECT_EQ(j["rearms"], 1);
}

TEST(CliReplay, ARotatedLogIsReplayedAcrossItsSegments) {
  const std::string log = temp_path("replay_rot.hlog");
  std::vector<std::string> args{hapticd_binary(), "run",
                                "--duration",     "25",
                                "--log",          log,
                                "--set",          "loop.clock=freerun",
                                "--set",          "telemetry.max_segment_mb=1",
                                "--set",          "telemetry.max_total_mb=0"};
  args.insert(args.end(), kCoupledDelayed.begin(), kCoupledDelayed.end());
  ASSERT_EQ(run_process(args).exit_code, 0);
  const json j = replay_json(log);
  EXPECT_EQ(j["segments"].size(), 3u);
  expect_reproduced(j, 25000);
}

TEST(CliReplay, ATamperedForceIsCaught) {
  const std::string log = temp_path("replay_t.hlog"), bad = temp_path("replay_bad.hlog");
  ASSERT_EQ(run_process({hapticd_binary(), "run", "--duration", "2", "--log", log, "--set",
                         "loop.clock=freerun"})
                .exit_code,
            0);
  telemetry::LogContents c = telemetry::read_log(log);
  c.records[1500].force_computed = std::nextafter(c.records[1500].force_computed, 1e9);
  telemetry::write_log_file(bad, c.header, c.records);
  const ProcessResult r = run_process({hapticd_binary(), "replay", bad});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(has(r.out, "NOT reproduced: 1 of 2000 ticks differ, the first at tick 1500"))
      << r.out;
  // A force of the direction check's pulse too.
  c = telemetry::read_log(log);
  ASSERT_TRUE(c.records[60].flags & telemetry::kFlagProbe);
  ASSERT_NE(c.records[60].force_commanded, 0.0) << "the pulse";
  c.records[60].force_commanded = -c.records[60].force_commanded;
  const std::string bad_pulse = temp_path("replay_bad_pulse.hlog");
  telemetry::write_log_file(bad_pulse, c.header, c.records);
  const ProcessResult p = run_process({hapticd_binary(), "replay", bad_pulse});
  EXPECT_EQ(p.exit_code, 1);
  EXPECT_TRUE(has(p.out, "NOT reproduced: 1 of 2000 ticks differ, the first at tick 60")) << p.out;
}

TEST(CliReplay, AnotherConfigurationGetsItsVerdictItsSummaryAndItsSeries) {
  const std::string log = temp_path("replay_w.hlog"), csv = temp_path("replay_w.csv");
  ASSERT_EQ(run_process({hapticd_binary(), "run", "--duration", "2", "--log", log, "--set",
                         "loop.clock=freerun"})
                .exit_code,
            0);
  const std::string other = temp_path("stiff.yaml");
  std::ofstream(other) << "wall:\n  stiffness: 6000\n";
  const ProcessResult r =
      run_process({hapticd_binary(), "replay", log, "--config", other, "--out", csv});
  EXPECT_EQ(r.exit_code, 3) << "the what-if's gate fails\n" << r.err;
  EXPECT_TRUE(has(r.out, "what-if: " + other)) << r.out;
  EXPECT_TRUE(has(r.out, "wall.stiffness must be <= 3600 N/m to pass (now 6000)")) << r.out;
  EXPECT_TRUE(has(r.out, "reproduced bit for bit")) << r.out;
  const json j = replay_json(log, {"--set", "wall.stiffness=1000"});
  EXPECT_EQ(j["other"]["gate"]["verdict"], "pass");
  EXPECT_LT(j["other"]["series"]["max_abs_force"].get<double>(),
            j["logged"]["max_abs_force"].get<double>())
      << "half the stiffness, on the same motion: less force";
  std::istringstream rows(read_file(csv));
  std::string line;
  std::getline(rows, line);
  EXPECT_EQ(line, "tick,position,force_logged,force_replayed,force_other");
  std::size_t n = 0, differ = 0;
  while (std::getline(rows, line)) {
    ++n;
    std::istringstream f(line);
    std::string cell[5];
    for (std::string& x : cell) std::getline(f, x, ',');
    EXPECT_EQ(cell[2], cell[3]) << line;
    differ += cell[3] != cell[4] ? 1 : 0;
  }
  EXPECT_EQ(n, 2000u);
  EXPECT_GT(differ, 500u) << "the stiffer wall commands other forces in contact";
}

}  // namespace
}  // namespace hapticd::testing
