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
#include "older_log.h"
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
                                "--duration",     "15",
                                "--log",          log,
                                "--set",          "loop.clock=freerun",
                                "--set",          "telemetry.max_segment_mb=1",
                                "--set",          "telemetry.max_total_mb=0"};
  args.insert(args.end(), kCoupledDelayed.begin(), kCoupledDelayed.end());
  ASSERT_EQ(run_process(args).exit_code, 0);
  const json j = replay_json(log);
  EXPECT_EQ(j["segments"].size(), 3u);  // 15000 records of 200 bytes: 2.9 MB
  expect_reproduced(j, 15000);
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

// A device of several joints: the delta of config/sim-delta.yaml pressed into its corner. Its
// log (format 4) carries every joint and the pose, replays every joint's torque bit for bit,
// and exports them.
TEST(CliReplay, ADeltaLogIsReproducedOnEveryJointAndExported) {
  const std::string log = temp_path("replay_delta.hlog"), sum = temp_path("replay_delta.json");
  const std::string csv = temp_path("replay_delta.csv");
  const ProcessResult run =
      run_process({hapticd_binary(), "run", "--config", source_dir() + "/config/sim-delta.yaml",
                   "--duration", "3", "--log", log, "--summary-json", sum});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const json s = json::parse(read_file(sum));
  EXPECT_GT(s["counters"]["loop"]["contact_ticks"].get<int>(), 1000);
  EXPECT_GE(s["passivity"]["energy_j"].get<double>(), 0.0) << s.dump(2);
  const json j = replay_json(log);
  expect_reproduced(j, 3000);
  EXPECT_EQ(j["reproduced"]["compared"], 3000);
  EXPECT_EQ(j["replayed"]["contact_ticks"], s["counters"]["loop"]["contact_ticks"]);

  ASSERT_EQ(run_process({hapticd_binary(), "export", log, "--out", csv}).exit_code, 0);
  std::istringstream rows(read_file(csv));
  std::string header, row;
  std::getline(rows, header);
  EXPECT_TRUE(has(header,
                  ",joints,joint2_position,joint3_position,joint2_force,joint3_force,"
                  "task_x,task_y,task_z,deepest_wall,wall_contact,pose_status"))
      << header;
  unsigned contact = 0;
  std::size_t rows_read = 0;
  while (std::getline(rows, row)) {
    std::vector<std::string> cells;
    std::istringstream fields(row);
    for (std::string c; std::getline(fields, c, ',');) cells.push_back(c);
    ASSERT_GE(cells.size(), 15u);
    // Format 4's eleven columns, before format 5's four (a client's force).
    const std::size_t first = cells.size() - 15;
    EXPECT_EQ(cells[first], "3") << row;
    contact |= static_cast<unsigned>(std::stoul(cells[first + 9]));
    ++rows_read;
  }
  EXPECT_EQ(rows_read, 3000u);
  EXPECT_EQ(contact, 0b100101u) << "the corner's walls: +x, +y and -z (0, 2 and 5)";
}

// A log of format 3 (before several joints: 112-byte records) is still replayed bit for bit
// and exported, its joints column 1.
TEST(CliReplay, AVersion3LogIsStillReplayedAndExported) {
  const std::string log = temp_path("replay_now.hlog"), old = temp_path("replay_v3.hlog");
  const std::string csv = temp_path("replay_v3.csv");
  ASSERT_EQ(run_process({hapticd_binary(), "run", "--duration", "1", "--log", log, "--set",
                         "loop.clock=freerun"})
                .exit_code,
            0);
  const std::string bytes = read_file(log);
  const telemetry::LogContents now =
      telemetry::read_log_bytes(std::as_bytes(std::span(bytes)), log);
  ASSERT_EQ(now.version, 5u);
  // Format 4 (176-byte records, before a client's force) replays as it is too.
  const std::string v4_log = temp_path("replay_v4.hlog");
  const std::vector<std::byte> v4 = older_log(4, now.header, now.records);
  std::ofstream(v4_log, std::ios::binary)
      .write(reinterpret_cast<const char*>(v4.data()), static_cast<std::streamsize>(v4.size()));
  expect_reproduced(replay_json(v4_log), 1000);
  const std::vector<std::byte> v3 = older_log(3, now.header, now.records);
  std::ofstream(old, std::ios::binary)
      .write(reinterpret_cast<const char*>(v3.data()), static_cast<std::streamsize>(v3.size()));
  expect_reproduced(replay_json(old), 1000);
  ASSERT_EQ(run_process({hapticd_binary(), "export", old, "--out", csv}).exit_code, 0);
  std::istringstream rows(read_file(csv));
  std::string header, row;
  std::getline(rows, header);
  std::getline(rows, row);
  // Joints 1 and the rest of format 4 zero, then format 5's four columns (no client force).
  const std::string one_joint = ",1,0,0,0,0,0,0,0,0,0,0,0,0,0,0";
  ASSERT_GT(row.size(), one_joint.size());
  EXPECT_EQ(row.substr(row.size() - one_joint.size()), one_joint) << row;
}

}  // namespace
}  // namespace hapticd::testing
