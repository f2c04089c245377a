#include "service/control/ctl_output.h"

#include <cstdio>
#include <sstream>

namespace hapticd::service {
namespace {

using nlohmann::json;

// A number with 4 significant digits (scaled), "-" when absent or null.
std::string num(const json& v, double scale = 1.0) {
  if (!v.is_number()) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v.get<double>() * scale);
  return buf;
}

std::string text(const json& v) { return v.is_string() ? v.get<std::string>() : "-"; }

// A count, whole ("-" when absent).
std::string count(const json& v) { return v.is_number_unsigned() ? v.dump() : num(v); }

std::string percentiles(const json& p) {
  if (!p.is_object()) return "-";
  return "p50 " + num(p["p50"]) + "  p99 " + num(p["p99"]) + "  p99.9 " + num(p["p999"]) +
         "  max " + num(p["max"]) + " us";
}

// The lines of an answer's "derated" (one joint: wall.stiffness) and "derated_walls".
std::string derated_lines(const json& j, const std::string& after) {
  std::string out;
  const auto line = [&](const json& d) {
    const std::string key = d.contains("key") ? text(d["key"]) : "wall.stiffness";
    out += "  DERATED       " + key + " " + num(d["configured"]) + " N/m configured, running at " +
           num(d["ran"]) + " N/m" + after + "\n";
  };
  if (j.contains("derated") && j["derated"].is_object()) line(j["derated"]);
  if (j.contains("derated_walls") && j["derated_walls"].is_array()) {
    for (const json& d : j["derated_walls"]) line(d);
  }
  return out;
}

std::string gate_line(const json& g) {
  if (!g.is_object()) return "-";
  const json& pass = g["passivity"];
  std::string line = text(g["verdict"]);
  if (pass.is_object()) {
    line += " (b_req " + num(pass["required_damping"]) + " <= " + num(pass["available_damping"]) +
            " N s/m allowed, max K " + num(pass["max_stiffness"]) + " N/m)";
  }
  for (const json& r : g.value("reasons", json::array())) line += "\n                " + text(r);
  return line;
}

}  // namespace

std::string status_text(const json& s) {
  std::ostringstream out;
  const json& dev = s["device"];
  out << "hapticd " << text(s["state"]) << ": " << text(s["driver"]) << " at " << num(s["rate_hz"])
      << " Hz (" << text(s["clock"]) << "), tick " << num(s["tick"]) << ", config "
      << text(s["config"]) << "\n";
  out << "  device        " << text(dev["description"]) << ": " << text(dev["state"])
      << (dev.value("output_enabled", false) ? ", output enabled" : ", output disabled")
      << ", last command " << num(dev["last_command"]) << " N\n";
  if (s.contains("walls") && s["walls"].is_array()) {  // a device of several joints
    for (std::size_t i = 0; i < s["walls"].size(); ++i) {
      const json& w = s["walls"][i];
      out << "  walls[" << i << "]      K " << num(w["stiffness"]) << " N/m  B "
          << num(w["damping"]) << " N s/m\n";
    }
  } else {
    out << "  wall          K " << num(s["wall"]["stiffness"]) << " N/m  B "
        << num(s["wall"]["damping"]) << " N s/m\n";
  }
  out << "  gate          " << gate_line(s["gate"]) << "\n";
  if (s.contains("direction_check") && s["direction_check"].is_object()) {
    const json& d = s["direction_check"];
    out << "  direction     " << text(d["state"]) << " (gain " << num(d["gain"]) << "), wall "
        << (d.value("armed", false) ? "armed" : "not armed") << "\n";
  }
  out << derated_lines(s, "");
  out << "  position      " << num(s["position"], 1e3) << " mm, penetration "
      << num(s["penetration"], 1e3) << " mm, force " << num(s["force_commanded"]) << " N\n";
  if (s.contains("joints") && s["joints"].is_array()) {
    for (std::size_t i = 0; i < s["joints"].size(); ++i) {
      out << "  joint " << i + 1 << "       position " << num(s["joints"][i]["position"])
          << ", torque " << num(s["joints"][i]["force_commanded"]) << "\n";
    }
    const json& x = s["task_position"];
    out << "  task position (" << num(x[0], 1e3) << ", " << num(x[1], 1e3) << ", " << num(x[2], 1e3)
        << ") mm\n";
  }
  out << "  wall energy   " << num(s["wall_energy_j"]) << " J (work the wall did on the device)\n";
  if (s.contains("observer_energy_j")) {
    out << "  passivity     observed energy " << num(s["observer_energy_j"]) << " J, damped "
        << num(s["passivity_damped_ticks"]) << " ticks\n";
  }
  out << "  wake latency  " << percentiles(s["wake_latency_us"]) << "\n";
  out << "  compute       " << percentiles(s["compute_us"]) << "\n";
  out << "  reloads       " << num(s["reloads"]) << "\n";
  // The run's counters, the loop's and the driver's, then the anomalies among them by name.
  if (s.contains("counters") && s["counters"].is_object()) {
    for (const auto& [source, counters] : s["counters"].items()) {
      out << "  " << source << std::string(source.size() < 14 ? 14 - source.size() : 1, ' ');
      const char* sep = "";
      for (const auto& [name, value] : counters.items()) {
        out << sep << name << " " << count(value);
        sep = ", ";
      }
      out << "\n";
    }
  }
  const json anomalies = s.value("anomalies", json::array());
  out << "  anomalies     " << (anomalies.empty() ? "none" : "") << "\n";
  for (const json& a : anomalies) {
    out << "    " << count(a["value"]) << " " << text(a["name"]) << " (" << text(a["source"])
        << ": " << text(a["meaning"]) << ")\n";
  }
  out << "  fault         " << (s["fault"].is_string() ? text(s["fault"]) : "none") << "\n";
  return out.str();
}

std::string reload_text(const json& r) {
  std::ostringstream out;
  if (r.value("op", "") == "move") {
    out << "scene move accepted: walls[" << num(r["index"]) << "] ";
    if (r["applied_at_tick"].is_number()) {
      out << "slides to its new point from tick " << num(r["applied_at_tick"]) << "\n";
    } else {
      out << "slides to its new point when output is next enabled\n";
    }
    return out.str();
  }
  if (r.contains("op")) {
    out << "scene " << r["op"].get<std::string>() << " accepted: walls[" << num(r["index"]) << "], "
        << num(r["walls"]) << " walls; ";
  } else {
    out << "reload accepted: ";
  }
  if (r["applied_at_tick"].is_number()) {
    out << "the new " << (r.contains("op") ? "walls govern" : "wall governs") << " from tick "
        << num(r["applied_at_tick"]);
  } else {
    out << "the new configuration applies when output is next enabled";
  }
  out << "\n  gate          " << gate_line(r["gate"]) << "\n";
  out << derated_lines(r, " (safety.gate: derate)");
  return out.str();
}

}  // namespace hapticd::service
