#include "service/commands/replay_command.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "gate/number_format.h"
#include "service/commands/replay.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "service/run/counters_report.h"
#include "service/run/gate_derate.h"
#include "telemetry/log_set.h"
#include "wiring/registry.h"

namespace hapticd::service {
namespace {

using gate::format_number;
using nlohmann::json;

json series_json(const ForceSeries& s) {
  return {{"max_abs_force", s.max_abs_force}, {"max_penetration", s.max_penetration},
          {"contact_ticks", s.contact_ticks}, {"saturated_ticks", s.saturated_ticks},
          {"wall_energy_j", s.wall_energy_j}, {"min_observer_energy_j", s.min_observer_energy_j},
          {"damped_ticks", s.damped_ticks}};
}

struct WhatIf {
  config::Config cfg;
  gate::GateReport gate;
};

json result_json(const std::string& log, const telemetry::LogSet& set, const ReplayResult& r,
                 const std::optional<WhatIf>& what_if) {
  json j;
  j["log"] = log;
  j["segments"] = set.segments;
  j["ticks"] = r.ticks.size();
  j["first_tick"] = r.ticks.empty() ? json(nullptr) : json(r.ticks.front());
  j["last_tick"] = r.ticks.empty() ? json(nullptr) : json(r.ticks.back());
  j["reloads"] = r.reloads;
  j["rearms"] = r.rearms;
  j["stopped"] = r.stopped.empty() ? json(nullptr) : json(r.stopped);
  j["note"] = r.note.empty() ? json(nullptr) : json(r.note);
  j["reproduced"] = {
      {"identical", r.differing == 0 && r.compared > 0},
      {"compared", r.compared},
      {"differing", r.differing},
      {"first_difference_tick", r.first_difference ? json(*r.first_difference) : json(nullptr)}};
  // The run's counters as the log recorded them when it ended (null: none recorded).
  const auto& counters = set.contents.counters;
  j["counters"] = counters.empty() ? json(nullptr) : counters_json(counters);
  j["anomalies"] = counters.empty() ? json(nullptr) : anomalies_json(counters);
  j["logged"] = series_json(r.logged);
  j["replayed"] = series_json(r.own);
  j["other"] = nullptr;
  if (what_if) {
    j["other"] = {{"config", what_if->cfg.source_name},
                  {"gate", gate::gate_to_json(what_if->gate)},
                  {"series", series_json(*r.other)}};
  }
  return j;
}

std::string row(const char* name, const std::string& a, const std::string& b) {
  char buf[160];
  if (b.empty()) {
    std::snprintf(buf, sizeof buf, "  %-18s %s\n", name, a.c_str());
  } else {
    std::snprintf(buf, sizeof buf, "  %-18s %-16s %s\n", name, a.c_str(), b.c_str());
  }
  return buf;
}

std::string result_text(const std::string& log, const telemetry::LogSet& set, const ReplayResult& r,
                        const std::optional<WhatIf>& what_if) {
  std::ostringstream os;
  os << "hapticd replay: " << log << ": " << r.ticks.size() << " ticks";
  if (!r.ticks.empty()) os << " (" << r.ticks.front() << " to " << r.ticks.back() << ")";
  os << ", " << set.segments.size() << (set.segments.size() == 1 ? " segment" : " segments") << ", "
     << r.reloads << (r.reloads == 1 ? " reload, " : " reloads, ") << r.rearms
     << (r.rearms == 1 ? " re-arming\n" : " re-armings\n");
  if (!r.stopped.empty()) os << "  stopped early  " << r.stopped << "\n";
  if (!r.note.empty()) os << "  note           " << r.note << "\n";
  os << "  forces         ";
  if (r.differing == 0) {
    os << "reproduced bit for bit by the log's own configuration (" << r.compared
       << " ticks compared)\n";
  } else {
    os << "NOT reproduced: " << r.differing << " of " << r.compared
       << " ticks differ, the first at tick " << *r.first_difference << "\n";
  }
  if (!set.contents.counters.empty()) counters_text(set.contents.counters, os, true);
  const auto col = [](const ForceSeries& s) {
    return std::array<std::string, 7>{
        format_number(s.max_abs_force) + " N", format_number(s.max_penetration * 1e3) + " mm",
        std::to_string(s.contact_ticks),       std::to_string(s.saturated_ticks),
        format_number(s.wall_energy_j) + " J", format_number(s.min_observer_energy_j) + " J",
        std::to_string(s.damped_ticks)};
  };
  const auto logged = col(r.logged);
  const auto other = what_if ? col(*r.other) : std::array<std::string, 7>{};
  if (what_if) {
    os << "what-if: " << what_if->cfg.source_name << "\n  gate               "
       << (what_if->gate.pass ? "pass" : "FAIL") << "\n";
    for (const std::string& reason : what_if->gate.reasons) os << "    " << reason << "\n";
  }
  os << row("", "logged", what_if ? "what-if" : "");
  const char* names[] = {"max |force|", "max penetration", "contact ticks", "saturated ticks",
                         "wall energy", "min observer E",  "damped ticks"};
  for (std::size_t i = 0; i < 7; ++i) os << row(names[i], logged[i], other[i]);
  return os.str();
}

bool write_csv(const std::string& path, const ReplayResult& r) {
  std::ofstream out(path);
  if (!out) {
    std::cerr << "hapticd: " << path << ": cannot open for writing: " << std::strerror(errno)
              << "\n";
    return false;
  }
  out << "tick,position,force_logged,force_replayed" << (r.other ? ",force_other" : "") << "\n";
  char line[160];
  for (std::size_t i = 0; i < r.ticks.size(); ++i) {
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g",
                  static_cast<unsigned long long>(r.ticks[i]), r.positions[i],
                  r.logged.commanded[i], r.own.commanded[i]);
    out << line;
    if (r.other) {
      std::snprintf(line, sizeof line, ",%.17g", r.other->commanded[i]);
      out << line;
    }
    out << "\n";
  }
  return finish_output(out, path);
}

// --config OTHER (with --set), or --set alone on the log's own configuration.
std::optional<WhatIf> what_if(const ReplayOptions& o, const telemetry::LogContents& log) {
  if (o.other.path.empty() && o.other.sets.empty()) return std::nullopt;
  WhatIf w;
  w.cfg = o.other.path.empty()
              ? load_config_text_checked(log.header.config_text,
                                         o.log_path + " (its configuration, with --set)", ".",
                                         o.other.sets)
              : load_config(o.other);
  const wiring::DriverEntry& driver = wiring::find_driver(w.cfg.device.driver);
  w.gate = gate::evaluate_gate(w.cfg, driver.declared_delay(w.cfg));
  // Under safety.gate: derate the what-if runs the stiffness `run` would (and says so).
  for (const Derating& d : derate_stiffness(w.cfg, driver.declared_delay(w.cfg), w.gate)) {
    std::cerr << "hapticd: what-if: DERATED (safety.gate: derate): " << d.key << " "
              << format_number(d.configured) << " N/m replayed at " << format_number(d.ran)
              << " N/m, the largest that passes\n";
  }
  return w;
}

}  // namespace

int replay_command(const ReplayOptions& options) {
  telemetry::LogSet set;
  try {
    set = telemetry::read_log_set(options.log_path);
  } catch (const telemetry::LogFormatError& e) {
    std::cerr << "hapticd: " << e.what() << "\n";
    return kExitUsage;
  }
  if (std::none_of(set.contents.records.begin(), set.contents.records.end(),
                   [](const telemetry::TickRecord& t) { return t.marker == 0; })) {
    std::cerr << "hapticd: " << options.log_path << ": holds no tick records to replay\n";
    return kExitUsage;
  }
  const std::optional<WhatIf> w = what_if(options, set.contents);
  const ReplayResult r = replay_log(set.contents, options.log_path, w ? &w->cfg : nullptr);
  if (r.ticks.front() != 0 && r.rearms == 0) {
    spdlog::warn(
        "{}: the log starts at tick {}, not 0 (its first segments were deleted): the "
        "replayed controller starts from rest there",
        options.log_path, r.ticks.front());
  }
  if (!r.stopped.empty()) spdlog::warn("{}: replay stopped early: {}", options.log_path, r.stopped);
  const std::string text = options.json ? result_json(options.log_path, set, r, w).dump(2) + "\n"
                                        : result_text(options.log_path, set, r, w);
  if (!write_stdout(text)) return kExitRuntimeFault;
  if (!options.out_path.empty() && !write_csv(options.out_path, r)) return kExitRuntimeFault;
  if (r.differing > 0) return kExitRuntimeFault;
  return w && !w->gate.pass ? kExitGateRefused : kExitOk;
}

}  // namespace hapticd::service
