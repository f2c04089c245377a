// The control socket driven through the built hapticctl, the way an operator does it: status,
// a reload that changes the wall at one tick boundary (seen in the tick log), reloads refused
// by the gate, by a change that needs a restart and by bad YAML while the old wall keeps
// running, SIGHUP, a latched fault cleared through the gate, and stop.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "daemon.h"
#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;
using telemetry::TickRecord;

// Every ordinary tick in contact must carry f = K p exactly (an undamped wall, no coupling):
// K_before before the boundary, K_after from it on.
void expect_wall_switches_at(const std::vector<TickRecord>& records, std::uint64_t boundary,
                             double k_before, double k_after) {
  int before = 0, after = 0;
  for (const TickRecord& r : records) {
    if (r.marker != telemetry::kMarkerNone || !(r.flags & telemetry::kFlagContact)) continue;
    const double k = r.tick < boundary ? k_before : k_after;
    ASSERT_EQ(r.force_computed, k * r.penetration)
        << "tick " << r.tick << " (boundary " << boundary << ")";
    ++(r.tick < boundary ? before : after);
  }
  EXPECT_GT(before, 50);
  EXPECT_GT(after, 50);
}

TEST(ControlSocket, StatusReloadsAndStopThroughHapticctl) {
  const std::string base = write_temp("base.yaml", pressing_config(2000));
  Daemon d({"--config", base, "--duration", "120"});
  ASSERT_TRUE(d.ready());
  struct stat st {};
  ASSERT_EQ(stat(d.socket().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0660u);

  json s = d.wait_status(
      [](const json& j) { return j["counters"]["loop"]["contact_ticks"].get<int>() > 300; });
  ASSERT_GT(s["counters"]["loop"]["contact_ticks"].get<int>(), 300) << s.dump();
  EXPECT_EQ(s["state"], "running");
  EXPECT_EQ(s["wall"]["stiffness"], 2000.0);
  EXPECT_EQ(s["gate"]["verdict"], "pass");
  EXPECT_TRUE(s["fault"].is_null());
  EXPECT_TRUE(s["wake_latency_us"]["p99"].is_number());
  EXPECT_TRUE(s["compute_us"]["max"].is_number());
  EXPECT_LT(s["wall_energy_j"].get<double>(), 0.0) << "pressed into: the wall took energy in";
  EXPECT_GE(s["observer_energy_j"].get<double>(), 0.0) << "a wall the gate passes";
  EXPECT_EQ(s["passivity_damped_ticks"], 0);
  const ProcessResult human = d.ctl({"status"});
  EXPECT_EQ(human.exit_code, 0) << human.err;
  EXPECT_TRUE(has(human.out, "hapticd running")) << human.out;
  EXPECT_TRUE(has(human.out, "K 2000 N/m")) << human.out;
  EXPECT_TRUE(has(human.out, "passivity     observed energy")) << human.out;

  // A passing reload: the new wall governs from the tick the daemon names.
  const ProcessResult ok =
      d.ctl({"--json", "reload", write_temp("k3000.yaml", pressing_config(3000))});
  ASSERT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  const json accepted = json::parse(ok.out)["reload"];
  ASSERT_TRUE(accepted["applied_at_tick"].is_number()) << ok.out;
  const auto boundary = accepted["applied_at_tick"].get<std::uint64_t>();
  EXPECT_EQ(accepted["gate"]["verdict"], "pass");

  // Refused: the gate (exit 3, its reason), a restart-only change and bad YAML (exit 2).
  const ProcessResult gate = d.ctl({"reload", write_temp("k5000.yaml", pressing_config(5000))});
  EXPECT_EQ(gate.exit_code, 3) << gate.err;
  EXPECT_TRUE(has(gate.err, "the gate refuses it")) << gate.err;
  EXPECT_TRUE(has(gate.err, "wall.stiffness must be <= 3600 N/m to pass (now 5000)")) << gate.err;
  const ProcessResult rate =
      d.ctl({"reload", write_temp("rate.yaml", pressing_config(3000, "  rate_hz: 500\n"))});
  EXPECT_EQ(rate.exit_code, 2) << rate.err;
  EXPECT_TRUE(has(rate.err, "loop.rate_hz: a new sample rate; that needs a restart")) << rate.err;
  const std::string bad = write_temp("bad.yaml", pressing_config(-5));
  const ProcessResult yaml = d.ctl({"reload", bad});
  EXPECT_EQ(yaml.exit_code, 2) << yaml.err;
  EXPECT_TRUE(has(yaml.err, bad + ":12: wall.stiffness: must be >= 0")) << yaml.err;

  // Enough ticks under the new wall to check it by (counted in ticks, not in time: a starved
  // loop skips periods).
  s = d.wait_status([&](const json& j) { return j["tick"].get<std::uint64_t>() > boundary + 200; });
  EXPECT_EQ(s["state"], "running") << "refusals leave the servo running";
  EXPECT_EQ(s["wall"]["stiffness"], 3000.0) << "the last accepted wall stays";
  EXPECT_EQ(s["reloads"], 1);
  const std::uint64_t tick_at_stop = s["tick"].get<std::uint64_t>();

  const ProcessResult stop = d.ctl({"stop"});
  EXPECT_EQ(stop.exit_code, 0) << stop.err;
  const ProcessResult end = d.wait();
  ASSERT_EQ(end.exit_code, 0) << end.err;
  EXPECT_TRUE(has(end.err, "reload from " + bad + " refused")) << end.err;
  const json summary = json::parse(read_file(d.summary()));
  EXPECT_EQ(summary["stop_reason"], "control socket: stop");
  EXPECT_EQ(summary["counters"]["loop"]["reloads"], 1);
  EXPECT_GE(summary["ticks"].get<std::uint64_t>(), tick_at_stop);

  const telemetry::LogContents log = telemetry::read_log(d.log());
  ASSERT_TRUE(log.trailing_reason.empty()) << log.trailing_reason;
  int accepted_markers = 0, refused_markers = 0;
  for (const TickRecord& r : log.records) {
    if (r.marker == telemetry::kMarkerReloadAccepted) {
      ++accepted_markers;
      EXPECT_EQ(r.tick, boundary);
    }
    if (r.marker == telemetry::kMarkerReloadRefused) {
      ++refused_markers;
      EXPECT_GT(r.tick, boundary);
    }
  }
  EXPECT_EQ(accepted_markers, 1);
  EXPECT_EQ(refused_markers, 3);
  ASSERT_EQ(log.reloads.size(), 1u);
  EXPECT_EQ(log.reloads[0].first_tick, boundary);
  EXPECT_TRUE(has(log.reloads[0].config_text, "stiffness: 3000")) << log.reloads[0].config_text;
  expect_wall_switches_at(log.records, boundary, 2000, 3000);
}

TEST(ControlSocket, SighupReloadsTheFileTheRunWasStartedWith) {
  const std::string file = write_temp("hup.yaml", pressing_config(2000));
  Daemon d({"--config", file, "--duration", "120"});
  ASSERT_TRUE(d.ready());
  d.wait_status(
      [](const json& j) { return j["counters"]["loop"]["contact_ticks"].get<int>() > 100; });
  write_temp("hup.yaml", pressing_config(2500));
  d.signal(SIGHUP);
  json s = d.wait_status([](const json& j) { return j["reloads"].get<int>() == 1; });
  EXPECT_EQ(s["wall"]["stiffness"], 2500.0) << s.dump();
  const auto reloaded_at = s["tick"].get<std::uint64_t>();
  s = d.wait_status(
      [&](const json& j) { return j["tick"].get<std::uint64_t>() > reloaded_at + 200; });
  write_temp("hup.yaml", pressing_config(9000));  // the gate refuses this one
  d.signal(SIGHUP);
  EXPECT_EQ(d.ctl({"stop"}).exit_code, 0);  // the SIGHUP is taken before the stop
  const ProcessResult end = d.wait();
  ASSERT_EQ(end.exit_code, 0) << end.err;
  EXPECT_TRUE(has(end.err, "reload from " + file + " refused: the gate refuses it")) << end.err;
  const telemetry::LogContents log = telemetry::read_log(d.log());
  ASSERT_EQ(log.reloads.size(), 1u);
  int refused = 0;
  for (const TickRecord& r : log.records) refused += r.marker == telemetry::kMarkerReloadRefused;
  EXPECT_EQ(refused, 1);
  expect_wall_switches_at(log.records, log.reloads[0].first_tick, 2000, 2500);
}

// A device moving at 0.6 m/s at start-up against safety.max_speed 0.3 faults at tick 1; the
// hand's damping stops it within a few ticks, so a re-armed loop runs on. (The simulated
// plant advances a period per read, so while the fault is held it stays where it faulted.)
std::vector<std::string> faulting_start(const std::string& x0, const std::string& setpoint) {
  return {"--on-fault", "hold", "--duration", "120", "--set", "device.sim.initial_position=" + x0,
          "--set", "device.sim.initial_velocity=0.6", "--set", "safety.max_speed=0.3", "--set",
          "device.sim.operator.damping=50",
          // A hand that damped holds the device firmly: the direction check sees a fraction of
          // the push's motion (the re-arming's check confirms it), and a firmer one would arm
          // the wall anyway, saying so.
          "--set", "safety.direction_check.on_no_motion=run", "--set",
          "device.sim.operator.setpoint={shape: constant, value: " + setpoint + "}"};
}

TEST(ControlSocket, ClearFaultReArmsThroughTheGateWithTheDeviceOutsideTheWall) {
  Daemon d(faulting_start("-0.02", "-0.02"));
  ASSERT_TRUE(d.ready());
  json s = d.wait_status([](const json& j) { return j["state"] == "faulted"; });
  ASSERT_EQ(s["state"], "faulted") << s.dump();
  EXPECT_TRUE(has(s["fault"].get<std::string>(), "impossible encoder data")) << s.dump();
  EXPECT_FALSE(s["device"]["output_enabled"].get<bool>());
  const ProcessResult cleared = d.ctl({"clear-fault"});
  EXPECT_EQ(cleared.exit_code, 0) << cleared.err;
  s = d.wait_status([](const json& j) { return j["state"] == "running"; });
  EXPECT_EQ(s["state"], "running");
  EXPECT_TRUE(s["device"]["output_enabled"].get<bool>());
  EXPECT_EQ(s["direction_check"]["state"], "confirmed") << "the re-arming checked again";
  EXPECT_TRUE(s["direction_check"]["armed"].get<bool>());
  EXPECT_TRUE(s["fault"].is_null());
  const ProcessResult again = d.ctl({"clear-fault"});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_TRUE(has(again.err, "no fault to clear: the run is running")) << again.err;
  EXPECT_EQ(d.ctl({"stop"}).exit_code, 0);
  const ProcessResult end = d.wait();
  EXPECT_EQ(end.exit_code, 0) << "a cleared fault does not fail the run\n" << end.err;
  const json summary = json::parse(read_file(d.summary()));
  EXPECT_TRUE(summary["faults"].empty());
  ASSERT_EQ(summary["cleared_faults"].size(), 1u);
  EXPECT_EQ(summary["device"]["final_command"], 0.0);
}

TEST(ControlSocket, ClearFaultIsRefusedWhileTheDeviceIsInsideTheWall) {
  Daemon d(faulting_start("0.005", "0.01"));  // it faults 5 mm deep
  ASSERT_TRUE(d.ready());
  ASSERT_EQ(d.wait_status([](const json& j) { return j["state"] == "faulted"; })["state"],
            "faulted");
  const ProcessResult refused = d.ctl({"clear-fault"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_TRUE(has(refused.err, "mm inside the wall: move it out first")) << refused.err;
  EXPECT_EQ(d.status()["state"], "faulted");
  EXPECT_EQ(d.ctl({"stop"}).exit_code, 0);
  const ProcessResult end = d.wait();
  EXPECT_EQ(end.exit_code, 1) << "the fault stands: " << end.err;
  EXPECT_EQ(json::parse(read_file(d.summary()))["device"]["output_enabled"], false);
}

// A device of several joints: the status names each wall, each joint and the pose (schema 4).
TEST(ControlSocket, StatusOfADeltaShowsEveryJointAndThePose) {
  Daemon d({"--config", source_dir() + "/config/sim-delta.yaml", "--duration", "120", "--set",
            "loop.clock=realtime", "--set", "device.sim.operator.setpoint.hold=200"});
  ASSERT_TRUE(d.ready());
  const json s = d.wait_status(
      [](const json& j) { return j["counters"]["loop"]["contact_ticks"].get<int>() > 300; });
  EXPECT_EQ(s["schema_version"], 8);
  ASSERT_TRUE(s["wall"].is_null()) << s.dump();
  ASSERT_EQ(s["walls"].size(), 6u);
  EXPECT_EQ(s["walls"][5]["stiffness"], 500.0);
  ASSERT_EQ(s["joints"].size(), 3u);
  EXPECT_EQ(s["joints"][0]["position"], s["position"]);
  // Pressed into the corner: beyond the +x, +y and -z faces (20 mm out, 85 mm up).
  EXPECT_GT(s["task_position"][0].get<double>(), 0.02) << s.dump();
  EXPECT_GT(s["task_position"][1].get<double>(), 0.02);
  EXPECT_LT(s["task_position"][2].get<double>(), 0.085);
  const ProcessResult human = d.ctl({"status"});
  EXPECT_EQ(human.exit_code, 0) << human.err;
  EXPECT_TRUE(has(human.out, "walls[5]      K 500 N/m")) << human.out;
  EXPECT_TRUE(has(human.out, "joint 3       position")) << human.out;
  EXPECT_TRUE(has(human.out, "task position (")) << human.out;
}

TEST(ControlSocket, HapticctlSaysWhenNoDaemonAnswers) {
  const ProcessResult r =
      run_process({hapticctl_binary(), "--socket", temp_path("nobody.sock"), "status"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(has(r.err, "nobody.sock: cannot connect: No such file or directory")) << r.err;
  const ProcessResult usage = run_process({hapticctl_binary(), "reload"});
  EXPECT_EQ(usage.exit_code, 2);
  const ProcessResult missing =
      run_process({hapticctl_binary(), "--socket", "x", "reload", temp_path("none.yaml")});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_TRUE(has(missing.err, "none.yaml: cannot read: No such file or directory")) << missing.err;
}

}  // namespace
}  // namespace hapticd::testing
