#include "service/run/run_summary.h"

#include <sstream>

#include "gate/number_format.h"
#include "service/run/counters_report.h"
#include "service/run/direction_report.h"

namespace hapticd::service {
namespace {

using gate::format_number;
using nlohmann::json;

json percentiles_us(const loop::LatencyHistogram* h) {
  if (h == nullptr || h->count() == 0) return nullptr;
  const auto us = [&](double q) { return static_cast<double>(h->percentile_ns(q)) / 1e3; };
  return {{"p50", us(0.5)}, {"p99", us(0.99)}, {"p999", us(0.999)}, {"max", us(1.0)}};
}

std::string line_us(const json& p) {
  if (p.is_null()) return "n/a (freerun: nothing waits)";
  return "p50 " + format_number(p["p50"].get<double>()) + "  p99 " +
         format_number(p["p99"].get<double>()) + "  p99.9 " +
         format_number(p["p999"].get<double>()) + "  max " + format_number(p["max"].get<double>()) +
         " us";
}

json passivity_json(const RunSummary& s) {
  const loop::PassivityResult& p = s.loop.passivity;
  if (!p.observed) return {{"mode", s.passivity_mode}};
  return {{"mode", s.passivity_mode},          {"energy_j", p.energy_j},
          {"min_energy_j", p.min_energy_j},    {"negative_ticks", p.negative_ticks},
          {"damped_ticks", p.damped_ticks},    {"max_damping", p.max_damping},
          {"damping_work_j", p.damping_work_j}};
}

void passivity_text(const RunSummary& s, std::ostream& os) {
  const loop::PassivityResult& p = s.loop.passivity;
  if (!p.observed) {
    os << "  passivity      observer off (safety.passivity_controller: off)\n";
    return;
  }
  os << "  passivity      observed energy " << format_number(p.energy_j) << " J, min "
     << format_number(p.min_energy_j) << " J, " << p.negative_ticks << " ticks below zero"
     << (p.negative_ticks > 0 ? " (THE LOOP PUT ENERGY INTO THE HAND)" : "") << "\n";
  if (s.passivity_mode == "damp") {
    os << "                 controller damped " << p.damped_ticks << " ticks, up to "
       << format_number(p.max_damping) << " N s/m, taking out " << format_number(p.damping_work_j)
       << " J\n";
  }
}

// The RT set-up, and how the loop kept time.
void timing_text(const RunSummary& s, const json& j, std::ostream& os) {
  if (s.realtime) {
    os << "  RT             "
       << (s.rt.fifo ? "SCHED_FIFO " + std::to_string(s.rt.priority) : "SCHED_OTHER")
       << (s.rt.memory_locked ? ", memory locked" : ", memory NOT locked")
       << (s.rt.cpu_dma_latency_zero ? ", cpu_dma_latency 0" : "")
       << (s.rt.cpu >= 0 ? ", CPU " + std::to_string(s.rt.cpu) : "") << "\n";
    os << "  wake latency   " << line_us(j["wake_latency_us"]) << "\n";
  }
  os << "  compute        " << line_us(j["compute_us"]) << "\n";
  os << "  overruns       " << counter_value(s.counters, "loop", "overruns") << " (missed ticks "
     << counter_value(s.counters, "loop", "missed_ticks") << ")\n";
}

// What the wall did: contact, its energy, the passivity observer, reloads, the operator.
void wall_text(const RunSummary& s, std::ostream& os) {
  const auto loop = [&](std::string_view name) { return counter_value(s.counters, "loop", name); };
  os << "  contact        " << loop("contact_ticks") << " ticks, max penetration "
     << format_number(s.loop.max_penetration * 1e3) << " mm, saturated " << loop("saturated_ticks")
     << " ticks\n";
  os << "  wall energy    " << format_number(s.loop.wall_energy_j)
     << " J (work the wall did on the device)\n";
  passivity_text(s, os);
  if (loop("reloads") > 0) {
    os << "  reloads        " << loop("reloads") << " swapped in at a tick boundary\n";
  }
  if (s.operator_work_j) {
    os << "  operator work  " << format_number(*s.operator_work_j)
       << " J (done by the operator on the device)\n";
  }
}

void log_text(const RunSummary& s, std::ostream& os) {
  if (s.log_path.empty()) return;
  os << "  tick log       " << s.log_path << ": " << s.log_records_written << " records, "
     << s.log_records_dropped << " dropped";
  if (s.log_io_errors) os << ", " << s.log_records_lost << " lost to WRITE ERRORS";
  if (s.log_segments > 1) os << ", " << s.log_segments << " segments";
  os << "\n";
  if (s.log_files_deleted > 0) {
    os << "                 (retention deleted " << s.log_files_deleted << " old files, "
       << format_number(static_cast<double>(s.log_bytes_deleted) / (1u << 20)) << " MB)\n";
  }
  if (!s.previous_log.empty()) {
    os << "                 (the previous log is now " << s.previous_log << ")\n";
  }
}

// The device's end state: zero force and output off, or loudly not.
void output_text(const RunSummary& s, std::ostream& os) {
  os << "  output         " << s.device_name << " " << s.device_state << ", "
     << (s.final_output_enabled ? "STILL ENABLED" : "disabled") << ", last command "
     << format_number(s.final_command) << " N";
  if (s.loopback) {
    os << " (peer: " << (s.peer_output_on ? "AMPLIFIER ON" : "amplifier off") << ", force "
       << format_number(s.peer_applied_force) << " N)";
  }
  os << "\n";
}

}  // namespace

json summary_to_json(const RunSummary& s) {
  json j;
  j["schema_version"] = kSummarySchemaVersion;
  j["ticks"] = s.loop.ticks;
  j["duration_s"] = static_cast<double>(s.loop.ticks) * s.sample_period_s;
  j["clock"] = s.realtime ? "realtime" : "freerun";
  j["wake_latency_us"] = s.realtime ? percentiles_us(s.wake_latency) : json(nullptr);
  j["compute_us"] = percentiles_us(s.compute_time);
  j["faults"] = s.faults;
  j["cleared_faults"] = s.cleared_faults;
  j["wall_energy_j"] = s.loop.wall_energy_j;
  j["stop_reason"] = s.stop_reason;
  j["max_penetration"] = s.loop.max_penetration;
  j["operator_work_j"] = s.operator_work_j ? json(*s.operator_work_j) : json(nullptr);
  j["log_path"] = s.log_path.empty() ? json(nullptr) : json(s.log_path);
  j["log_records_written"] = s.log_records_written;
  j["log_records_dropped"] = s.log_records_dropped;
  j["log_records_lost"] = s.log_records_lost;
  j["log_io_errors"] = s.log_io_errors;
  j["log_segments"] = s.log_segments;
  j["log_files_deleted"] = s.log_files_deleted;
  j["log_bytes_deleted"] = s.log_bytes_deleted;
  j["previous_log"] = s.previous_log.empty() ? json(nullptr) : json(s.previous_log);
  j["output_was_enabled"] = s.output_was_enabled;
  j["device"] = {{"name", s.device_name},
                 {"description", s.device_description},
                 {"notices", s.device_notices},
                 {"state", s.device_state},
                 {"final_command", s.final_command},
                 {"output_enabled", s.final_output_enabled}};
  j["counters"] = counters_json(s.counters);
  j["anomalies"] = anomalies_json(s.counters);
  j["loopback"] =
      s.loopback ? json{{"applied_force", s.peer_applied_force}, {"output_on", s.peer_output_on}}
                 : json(nullptr);
  j["rt"] = {{"sched_fifo", s.rt.fifo},
             {"priority", s.rt.priority},
             {"memory_locked", s.rt.memory_locked},
             {"cpu", s.rt.cpu},
             {"timer_slack_1ns", s.rt.timer_slack_1ns},
             {"cpu_dma_latency_zero", s.rt.cpu_dma_latency_zero},
             {"others_off_rt_cpu", s.rt.others_off_rt_cpu},
             {"warnings", s.rt.warnings}};
  j["gate"] = s.gate;
  j["passivity"] = passivity_json(s);
  j["direction_check"] = direction_json(s.loop.direction);
  derated_to_json(s.derated, j);
  return j;
}

void derated_to_json(const std::vector<Derating>& derated, json& j) {
  j["derated"] = nullptr;
  j["derated_walls"] = nullptr;
  for (const Derating& d : derated) {
    const json one = {{"key", d.key}, {"configured", d.configured}, {"ran", d.ran}};
    if (d.key == "wall.stiffness") {
      j["derated"] = one;
      continue;
    }
    if (j["derated_walls"].is_null()) j["derated_walls"] = json::array();
    json w = one;
    w["wall"] = d.wall;
    j["derated_walls"].push_back(w);
  }
}

std::string derated_text(const std::vector<Derating>& derated, const std::string& ran) {
  std::string out;
  for (const Derating& d : derated) {
    out += "  DERATED       " + d.key + " " + format_number(d.configured) + " N/m configured, " +
           ran + " " + format_number(d.ran) + " N/m\n";
  }
  return out;
}

std::string summary_to_text(const RunSummary& s) {
  const json j = summary_to_json(s);
  std::ostringstream os;
  os << "hapticd run: " << s.loop.ticks << " ticks, "
     << format_number(j["duration_s"].get<double>()) << " s at "
     << format_number(1.0 / s.sample_period_s) << " Hz (" << j["clock"].get<std::string>()
     << "), stopped by " << s.stop_reason
     << (s.output_was_enabled ? "" : " before output was enabled") << "\n";
  if (!s.derated.empty()) {
    os << derated_text(s.derated, "ran at")
       << "  (safety.gate: derate: the largest that passes the gate; the last derating of the "
          "run, at start or by a reload)\n";
  }
  timing_text(s, j, os);
  if (s.output_was_enabled) {
    direction_text(s.loop.direction, loop::is_direction_refusal(s.loop.fault.cause), os);
  }
  wall_text(s, os);
  log_text(s, os);
  output_text(s, os);
  counters_text(s.counters, os);
  os << "  faults         "
     << (s.faults.empty() ? std::string("none") : std::to_string(s.faults.size())) << "\n";
  for (const std::string& f : s.faults) os << "    " << f << "\n";
  if (!s.cleared_faults.empty()) {
    os << "  cleared        " << s.cleared_faults.size() << " (by clear-fault; the run went on)\n";
    for (const std::string& f : s.cleared_faults) os << "    " << f << "\n";
  }
  return os.str();
}

}  // namespace hapticd::service
