// The direction check, the runaway guard and identify's direction, as a user meets them: on the
// simulated device and through every loopback peer this build has, a motor wired the other way
// round (device.sim.force_reversed) is refused before its wall acts, naming the driver's own
// setting that reverses the force; with the check off the runaway guard stops the wall that
// pulls; identify reports the reversal and prints no configuration.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

struct Example {
  std::string config;       // "" for the embedded sim.yaml
  std::string reverse_key;  // the setting the refusal must name
};

std::vector<Example> examples() {
  std::vector<Example> e = {{"", "device.sim.force_reversed: false (it is true)"}};
#if HAPTICD_TEST_WITH_HID
  e.push_back({"hid-report.yaml", "device.hid.report.output.force.scale: -0.001 (it is 0.001)"});
  e.push_back({"hid-pid.yaml", "device.hid.pid.direction_deg: "});
#endif
#if HAPTICD_TEST_WITH_CAN
  e.push_back({"can-cia402.yaml", "device.can.torque_per_force: -0.01 (it is 0.01)"});
  e.push_back({"can-odrive.yaml", "device.can.torque_per_force: -0.015625 (it is 0.015625)"});
#endif
#if HAPTICD_TEST_WITH_GPIO
  e.push_back({"gpio.yaml", "device.gpio.direction_positive: low (it is high)"});
#endif
#if HAPTICD_TEST_WITH_EVDEV
  e.push_back({"evdev.yaml", "device.evdev.direction_deg: "});
#endif
  return e;
}

std::vector<std::string> run_args(const Example& e, const std::string& summary,
                                  std::vector<std::string> sets) {
  std::vector<std::string> cmd = {hapticd_binary(), "run",  "--duration", "2",
                                  "--summary-json", summary};
  if (!e.config.empty()) {
    cmd.insert(cmd.end(), {"--loopback", "--config", example(e.config)});
  }
  cmd.insert(cmd.end(), {"--set", "loop.clock=freerun"});
  for (const std::string& s : sets) cmd.insert(cmd.end(), {"--set", s});
  return cmd;
}

TEST(CliDirectionCheck, EveryPeerWithItsForceReversedIsRefusedNamingTheSettingThatFixesIt) {
  for (const Example& e : examples()) {
    SCOPED_TRACE(e.config.empty() ? "sim" : e.config);
    const std::string summary = temp_path("reversed.json");
    const ProcessResult r = run_process(run_args(e, summary, {"device.sim.force_reversed=true"}));
    EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
    EXPECT_TRUE(has(r.err, "the direction check found the force reversed")) << r.err;
    EXPECT_TRUE(has(r.err, e.reverse_key)) << r.err;
    EXPECT_TRUE(has(r.out, "stopped by direction check")) << r.out;
    EXPECT_TRUE(has(r.out, "direction      REVERSED")) << r.out;
    const json j = json::parse(read_file(summary));
    EXPECT_EQ(j["schema_version"], 8);
    EXPECT_EQ(j["direction_check"]["state"], "reversed");
    EXPECT_LT(j["direction_check"]["gain"].get<double>(), -0.2);
    EXPECT_EQ(j["counters"]["loop"]["contact_ticks"], 0) << "no wall ever acted";
    EXPECT_EQ(j["device"]["final_command"], 0.0);
    EXPECT_FALSE(j["device"]["output_enabled"].get<bool>());
  }
}

TEST(CliDirectionCheck, EveryPeerAsConfiguredIsConfirmedAndRendersItsWall) {
  for (const Example& e : examples()) {
    SCOPED_TRACE(e.config.empty() ? "sim" : e.config);
    const std::string summary = temp_path("confirmed.json");
    const ProcessResult r = run_process(run_args(e, summary, {}));
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_TRUE(has(r.err, "direction check: confirmed")) << r.err;
    const json j = json::parse(read_file(summary));
    EXPECT_EQ(j["direction_check"]["state"], "confirmed");
    EXPECT_GT(j["direction_check"]["gain"].get<double>(), 0.2);
    EXPECT_GT(j["counters"]["loop"]["contact_ticks"].get<int>(), 100);
  }
}

TEST(CliDirectionCheck, WithTheCheckOffTheRunawayGuardStopsTheWallThatPulls) {
  for (const Example& e : examples()) {
    SCOPED_TRACE(e.config.empty() ? "sim" : e.config);
    const std::string summary = temp_path("runaway.json");
    const ProcessResult r = run_process(run_args(
        e, summary, {"device.sim.force_reversed=true", "safety.direction_check.mode=off"}));
    EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
    EXPECT_TRUE(has(r.err, "the wall is not holding")) << r.err;
    EXPECT_TRUE(has(r.out, "not checked (safety.direction_check.mode: off)")) << r.out;
    const json j = json::parse(read_file(summary));
    EXPECT_EQ(j["stop_reason"], "fault");
    EXPECT_EQ(j["device"]["final_command"], 0.0);
    EXPECT_FALSE(j["device"]["output_enabled"].get<bool>());
    EXPECT_EQ(j["loopback"]["applied_force"], 0.0);
  }
}

TEST(CliDirectionCheck, ADeviceHeldFirmlyIsRefusedOrRunsUncheckedAsConfigured) {
  // A grip ten thousand times the demo hand's, held where it starts: the pulse cannot move
  // the device.
  const std::vector<std::string> held = {"device.sim.operator.stiffness=3e6",
                                         "device.sim.operator.damping=3000",
                                         "device.sim.operator.setpoint={shape: constant, "
                                         "value: -0.02}"};
  const std::string summary = temp_path("held.json");
  ProcessResult r = run_process(run_args({}, summary, held));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_TRUE(has(r.err, "the direction check saw no motion")) << r.err;
  EXPECT_TRUE(has(r.err, "Let go of the device")) << r.err;
  std::vector<std::string> run_anyway = held;
  run_anyway.push_back("safety.direction_check.on_no_motion=run");
  r = run_process(run_args({}, summary, run_anyway));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(has(r.err, "the wall is armed UNCHECKED")) << r.err;
  EXPECT_TRUE(has(r.out, "the wall ran UNCHECKED")) << r.out;
  EXPECT_EQ(json::parse(read_file(summary))["direction_check"]["state"], "no motion");
}

TEST(CliDirectionCheck, ADeviceNeverAtRestIsRefusedAfterTheTimeOut) {
  const std::string summary = temp_path("moving.json");
  const ProcessResult r = run_process(
      run_args({}, summary,
               {"device.sim.operator.setpoint={shape: sine, offset: -0.02, amplitude: 0.01, "
                "frequency_hz: 3}",
                "safety.direction_check.rest_timeout_ms=400"}));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_TRUE(has(r.err, "never at rest")) << r.err;
  const json j = json::parse(read_file(summary));
  EXPECT_EQ(j["direction_check"]["state"], "never at rest");
  EXPECT_EQ(j["direction_check"]["ticks"], 400);
}

TEST(CliDirectionCheck, TheCheckIsInTheTickLogAndReplayReproducesTheRunBitForBit) {
  const std::string log = temp_path("probe.hlog");
  ProcessResult r = run_process(
      {hapticd_binary(), "run", "--duration", "2", "--log", log, "--set", "loop.clock=freerun"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = temp_path("probe.csv");
  r = run_process({hapticd_binary(), "export", log, "--out", csv});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string rows = read_file(csv);
  EXPECT_TRUE(has(rows.substr(0, rows.find('\n')), ",runaway,probe")) << "the check's columns";
  // runaway 0, probe 1, then format 4's columns of one joint and format 5's four.
  EXPECT_TRUE(has(rows, ",0,1,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n")) << "ticks of the check are marked";
  r = run_process({hapticd_binary(), "replay", log, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["reproduced"]["differing"], 0);
  EXPECT_TRUE(j["reproduced"]["identical"].get<bool>());
  EXPECT_GT(j["reproduced"]["compared"].get<int>(), 1800) << "every tick after the check";
}

TEST(CliIdentifyDirection, EveryPeerWithItsForceReversedIsReportedAndNoConfigurationPrinted) {
  for (const Example& e : examples()) {
    SCOPED_TRACE(e.config.empty() ? "sim" : e.config);
    std::vector<std::string> cmd = {hapticd_binary(),
                                    "identify",
                                    "--json",
                                    "--duration",
                                    "3",
                                    "--set",
                                    "device.sim.force_reversed=true"};
    if (!e.config.empty()) cmd.insert(cmd.end(), {"--loopback", "--config", example(e.config)});
    ProcessResult r = run_process(cmd);
    EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
    const json j = json::parse(r.out);
    EXPECT_EQ(j["schema_version"], 3);
    EXPECT_EQ(j["force_direction"], "reversed");
    EXPECT_LT(j["mass"].get<double>(), 0.0) << "a reversed force fits a negative mass";
    EXPECT_LT(j["damping"].get<double>(), 0.0);
    EXPECT_TRUE(has(j["reverse_with"].get<std::string>(), e.reverse_key)) << j.dump();
    cmd.erase(cmd.begin() + 2);  // the text
    r = run_process(cmd);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_TRUE(has(r.out, "FORCE REVERSED")) << r.out;
    EXPECT_FALSE(has(r.out, "paste into the configuration")) << r.out;
  }
}

}  // namespace
}  // namespace hapticd::testing
