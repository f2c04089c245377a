// What a `hapticd run` did: the numbers for the human summary and for --summary-json.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "base/counters.h"
#include "loop/latency_histogram.h"
#include "loop/rt_setup.h"
#include "loop/servo_loop.h"
#include "service/run/gate_derate.h"

namespace hapticd::service {

// The shape of --summary-json (and of `hapticctl status`, which shares its objects). Each
// change of shape is a new version, listed in docs/operations.md: 1 had no schema_version
// key; 2 added it, direction_check, and the status answer's direction_check; 3 added the
// gate's workspace (several task axes); 4 the runs of several joints; 5 the workspace's
// joint_damping (device.damping per joint); 6 and 7 the scene's walls; 8 counters.can's
// emcys_in_stop.
inline constexpr int kSummarySchemaVersion = 8;

struct RunSummary {
  bool realtime = true;
  double sample_period_s = 0.0;
  loop::LoopResult loop;
  const loop::LatencyHistogram* wake_latency = nullptr;
  const loop::LatencyHistogram* compute_time = nullptr;
  loop::RtStatus rt;
  std::vector<std::string> faults;
  // Faults latched and then cleared by `hapticctl clear-fault` (--on-fault hold): reported,
  // but the run went on and they do not make its exit code 1.
  std::vector<std::string> cleared_faults;
  std::optional<double> operator_work_j;  // sim only
  std::string log_path;                   // "" when no log was written
  std::uint64_t log_records_written = 0;
  std::uint64_t log_records_dropped = 0;  // by the full RT ring
  std::uint64_t log_records_lost = 0;     // to write errors (disk full, size limit)
  std::uint64_t log_io_errors = 0;
  std::uint32_t log_segments = 0;       // files of this run's log (rotation), 0 with no log
  std::uint64_t log_files_deleted = 0;  // by the retention cap (telemetry.max_total_mb)
  std::uint64_t log_bytes_deleted = 0;
  std::string previous_log;                 // where a log already at log_path was kept, "" if none
  std::string stop_reason;                  // "duration", "signal SIGTERM", "fault"
  bool output_was_enabled = false;          // false: stopped before output was ever enabled
  std::string device_name;                  // the driver
  std::string device_description;           // DeviceInfo::description
  std::vector<std::string> device_notices;  // Device::notices
  std::string device_state;                 // after the run, before close: "configured", "faulted"
  // The loop's counters and the driver's (counters_report.h), read once output was disabled.
  std::vector<base::CounterReading> counters;
  double final_command = 0.0;         // Device::last_command() once output was disabled
  bool final_output_enabled = false;  // Device::output_enabled() then
  bool loopback = false;              // a simulated peer stood in for the device
  double peer_applied_force = 0.0;    // what the peer's plant felt last (loopback)
  bool peer_output_on = false;
  nlohmann::json gate;
  std::string passivity_mode;  // safety.passivity_controller: "off", "observe", "damp"
  // safety.gate: derate ran walls at a lower stiffness than configured (the last derating).
  std::vector<Derating> derated;
};

nlohmann::json summary_to_json(const RunSummary& s);
// Into `j`: "derated", one joint's wall.stiffness {key, configured, ran}, and "derated_walls",
// several joints' [{key, wall, configured, ran}], each null when not derated.
void derated_to_json(const std::vector<Derating>& derated, nlohmann::json& j);
// "  DERATED  walls[1].stiffness 900 N/m configured, ran at 700 N/m\n" for each.
std::string derated_text(const std::vector<Derating>& derated, const std::string& ran);
// {"name": value, ...}: a driver's counters for the summary and `hapticctl status`.
std::string summary_to_text(const RunSummary& s);

}  // namespace hapticd::service
