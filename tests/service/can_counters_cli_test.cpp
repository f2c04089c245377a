// The CAN driver's counters where a person looks at a run's health: the summary (JSON and
// text) of `hapticd run --loopback` with each CAN example (the gantry's two nodes too), and
// `hapticctl status` while it runs, list them under counters.can (Device::counters,
// docs/drivers/can.md; the generic per-driver check, status included, is driver_counters_test.cpp).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "process.h"

namespace hapticd::testing {
namespace {

#if HAPTICD_TEST_WITH_CAN

using nlohmann::json;

// What a run that met nothing unusual shows as zero.
const char* const kAnomalies[] = {
    "malformed_messages", "wrong_length",   "unknown_ids",    "tx_queue_full",
    "lost_arbitration",   "error_warnings", "bus_errors",     "controller_restarts",
    "sdo_aborts",         "over_vel_limit", "internal_limit", "unsolicited_estimates"};

// Returns the summary.
json expect_counted(const std::string& config, int frames_out_per_tick, int frames_in_per_tick) {
  const std::string sum = temp_path("can-counters.json");
  const ProcessResult r =
      run_process({hapticd_binary(), "run", "--loopback", "--config", example(config), "--duration",
                   "1", "--set", "loop.clock=freerun", "--summary-json", sum});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  if (r.exit_code != 0) return json::object();
  const json summary = json::parse(read_file(sum));
  const json c = summary["counters"]["can"];
  EXPECT_TRUE(c.is_object()) << read_file(sum);
  // 1000 ticks, each with its frames out and the drive's answer in, and start-up's SDOs.
  EXPECT_GE(c["frames_sent"].get<int>(), 1000 * frames_out_per_tick) << c.dump();
  EXPECT_GE(c["frames_received"].get<int>(), 1000 * frames_in_per_tick) << c.dump();
  EXPECT_EQ(c["emcy_resets"], 0) << c.dump();
  for (const char* name : kAnomalies) EXPECT_EQ(c[name], 0) << name << ": " << c.dump();
  EXPECT_NE(r.out.find("frames_sent"), std::string::npos) << "the text summary lists it\n" << r.out;
  return summary;
}

TEST(CliCanCounters, TheSummaryListsTheCia402DriversCounters) {
  expect_counted("can-cia402.yaml", 2, 1);  // RPDO and SYNC (and hapticd's heartbeat)
}

TEST(CliCanCounters, TheSummaryListsTheOdriveDriversCounters) {
  expect_counted("can-odrive.yaml", 2, 1);  // Set_Input_Torque and the estimates request
}

// Two nodes as a gantry, one simulated drive each on one bus: each node's RPDO and one SYNC
// out, each node's TPDO in, and the example's hand pressing the gantry into its wall.
TEST(CliCanCounters, TheSummaryListsTheGantrysCountersAndItsHandMetTheWall) {
  const json summary = expect_counted("can-gantry.yaml", 3, 2);
  EXPECT_GT(summary["counters"]["loop"]["contact_ticks"].get<int>(), 100) << summary.dump();
  EXPECT_EQ(summary["gate"]["workspace"]["joint_damping"].size(), 2u) << summary.dump();
}

#endif

}  // namespace
}  // namespace hapticd::testing
