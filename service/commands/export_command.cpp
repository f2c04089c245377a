#include "service/commands/export_command.h"

#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <utility>

#include "base/errno_text.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "telemetry/log_reader.h"
#include "telemetry/log_set.h"

namespace hapticd::service {

namespace {

// One CSV row a record: every field of the log format, flags as 0/1 columns.
void write_rows(const telemetry::LogContents& log, std::ostream& out) {
  out << "tick,scheduled_s,wake_latency_us,compute_us,position,penetration,velocity,"
         "force_computed,force_commanded,contact,saturated,fault,overrun,no_pull_clamped,stale,"
         "unarmed,non_finite,sequence_gap,no_position,device_status,sample_time_s,sequence,"
         "fault_cause,fault_class,fault_code,marker,observer_energy_j,passivity_damping,"
         "passivity_damped,stepped,held,runaway,probe,joints,joint2_position,joint3_position,"
         "joint2_force,joint3_force,task_x,task_y,task_z,deepest_wall,wall_contact,pose_status,"
         "client_fx,client_fy,client_fz,client_force_limited\n";
  char row[768];
  for (const telemetry::TickRecord& r : log.records) {
    const auto bit = [&](std::uint32_t f) { return (r.flags & f) ? 1 : 0; };
    std::snprintf(
        row, sizeof row,
        "%llu,%.9f,%.3f,%.3f,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%u,"
        "%.9f,%u,%u,%u,%u,%u,%.17g,%.17g,%d,%d,%d,%d,%d",
        static_cast<unsigned long long>(r.tick), static_cast<double>(r.scheduled_ns) * 1e-9,
        r.wake_latency_ns * 1e-3, r.compute_ns * 1e-3, r.position, r.penetration, r.velocity,
        r.force_computed, r.force_commanded, bit(telemetry::kFlagContact),
        bit(telemetry::kFlagSaturated), bit(telemetry::kFlagFault), bit(telemetry::kFlagOverrun),
        bit(telemetry::kFlagNoPullClamped), bit(telemetry::kFlagStale),
        bit(telemetry::kFlagUnarmed), bit(telemetry::kFlagNonFinite),
        bit(telemetry::kFlagSequenceGap), bit(telemetry::kFlagNoPosition), r.device_status,
        static_cast<double>(r.sample_time_ns) * 1e-9, r.sequence, unsigned{r.fault_cause},
        unsigned{r.fault_class}, r.fault_code, r.marker, r.observer_energy_j, r.passivity_damping,
        bit(telemetry::kFlagPassivityDamped), bit(telemetry::kFlagStepped),
        bit(telemetry::kFlagHeld), bit(telemetry::kFlagRunaway), bit(telemetry::kFlagProbe));
    out << row;
    // Format 4's fields (a device of several joints; `joints` 1 for a log before it).
    std::snprintf(row, sizeof row, ",%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%u,%u,%u",
                  r.joints == 0 ? 1u : unsigned{r.joints}, r.joint_position[0], r.joint_position[1],
                  r.joint_force[0], r.joint_force[1], r.task_position[0], r.task_position[1],
                  r.task_position[2], unsigned{r.deepest_wall}, unsigned{r.wall_contact},
                  unsigned{r.pose_status});
    out << row;
    // Format 5's: a client's commanded force (0 in a log before it).
    std::snprintf(row, sizeof row, ",%.17g,%.17g,%.17g,%d\n", r.client_force[0], r.client_force[1],
                  r.client_force[2], bit(telemetry::kFlagClientForceLimited));
    out << row;
  }
}

// What the log lost, said once the rows are out: ticks the writer marked missing, damaged
// stretches skipped, a cut end.
void warn_losses(const std::string& log_path, const telemetry::LogContents& log) {
  if (log.dropped_records > 0) {
    spdlog::warn(
        "{}: {} records are missing, marked by the writer (dropped by a full ring or lost to "
        "write errors; gaps in 'tick')",
        log_path, log.dropped_records);
  }
  for (const telemetry::SkippedRegion& r : log.skipped) {
    spdlog::warn("{}: {}; skipped {} damaged bytes to the next intact block (gap in 'tick')",
                 log_path, r.reason, r.bytes);
  }
  if (!log.trailing_reason.empty()) {
    spdlog::warn("{}: {}; {} bytes after the last complete block ignored", log_path,
                 log.trailing_reason, log.trailing_bytes_ignored);
  }
}

}  // namespace

int export_command(const std::string& log_path, const std::string& out_path) {
  telemetry::LogContents log;
  try {
    telemetry::LogSet set = telemetry::read_log_set(log_path);  // every segment, in order
    if (set.segments.size() > 1) {
      spdlog::info("{}: {} segments, {} to {}", log_path, set.segments.size(), set.segments.front(),
                   set.segments.back());
    }
    log = std::move(set.contents);
  } catch (const telemetry::LogFormatError& e) {
    std::cerr << "hapticd: " << e.what() << "\n";
    return kExitUsage;
  }
  std::ofstream file;
  if (!out_path.empty()) {
    errno = 0;
    file.open(out_path);
    if (!file) {
      std::cerr << "hapticd: " << out_path << ": cannot open for writing: "
                << (errno != 0 ? base::errno_text(errno) : "failed") << "\n";
      return kExitUsage;
    }
  }
  std::ostream& out = out_path.empty() ? std::cout : file;
  errno = 0;  // finish_output reports the error of the write that failed
  write_rows(log, out);
  if (!finish_output(out, out_path.empty() ? "standard output" : out_path)) {
    return kExitRuntimeFault;
  }
  warn_losses(log_path, log);
  return kExitOk;
}

}  // namespace hapticd::service
