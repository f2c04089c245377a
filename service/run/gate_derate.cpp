#include "service/run/gate_derate.h"

#include <cstdio>
#include <string>

#include "config/config_loader.h"
#include "gate/number_format.h"

namespace hapticd::service {
namespace {

// %.17g round-trips a double: the recorded document gets the value that ran to the last bit.
std::string exact(double v) {
  char k[40];
  std::snprintf(k, sizeof k, "%.17g", v);
  return k;
}

// The walls of several joints: each one the gate does not pass alone, lowered to its own
// largest passing K; empty when one that fails has no such K (or none fails alone).
std::vector<Derating> wall_deratings(const config::Config& cfg, const gate::WorkspaceReport& w) {
  std::vector<Derating> out;
  for (std::size_t i = 0; i < w.walls.size() && i < cfg.walls.size(); ++i) {
    const gate::WallVerdict& v = w.walls[i];
    if (v.passive) continue;
    const double k = cfg.walls[i].law.stiffness;
    if (!v.reached || v.max_stiffness.kind != analysis::StiffnessLimit::Kind::kBounded ||
        !(v.max_stiffness.value < k)) {
      return {};  // the stiffness is not what fails this wall, or no stiffness passes it
    }
    out.push_back({"walls[" + std::to_string(i) + "].stiffness", i, k, v.max_stiffness.value});
  }
  return out;
}

}  // namespace

std::vector<Derating> derate_stiffness(config::Config& cfg, int device_delay_samples,
                                       gate::GateReport& report) {
  if (report.pass || cfg.safety.gate != config::GateMode::kDerate) return {};
  std::vector<Derating> lowered;
  config::Config next = cfg;
  if (report.workspace) {
    lowered = wall_deratings(cfg, *report.workspace);
    for (const Derating& d : lowered) next.walls[d.wall].law.stiffness = d.ran;
  } else {
    const analysis::StiffnessLimit& limit = report.passivity.max_stiffness;
    if (!report.passivity.passive && limit.kind == analysis::StiffnessLimit::Kind::kBounded &&
        limit.value < cfg.wall.stiffness) {
      lowered.push_back({"wall.stiffness", 0, cfg.wall.stiffness, limit.value});
      next.wall.stiffness = limit.value;
    }
  }
  if (lowered.empty()) return {};  // the stiffness is not what fails, or no stiffness passes
  gate::GateReport derated = gate::evaluate_gate(next, device_delay_samples);
  if (!derated.pass) {
    if (report.workspace) {
      report.reasons.push_back(
          "safety.gate: derate lowered each failing wall to its largest passing K and the gate "
          "still refuses (walls acting together): lower them further yourself, then check again");
    }
    return {};
  }
  std::string notes;
  for (const Derating& d : lowered) {
    notes += "# safety.gate: derate ran " + d.key + " at " + exact(d.ran) + " N/m (configured " +
             gate::format_number(d.configured, 17) + ")\n";
    next.effective_yaml = config::with_setting(next.effective_yaml, {d.key, exact(d.ran), {}});
  }
  next.effective_yaml = notes + next.effective_yaml;
  cfg = std::move(next);
  report = std::move(derated);
  return lowered;
}

bool gate_allows(const gate::GateReport& report, const config::Config& cfg) {
  return report.pass || cfg.safety.gate == config::GateMode::kWarn;
}

std::string why_not_movable(const gate::GateReport& report) {
  if (!report.workspace) return "a device of one joint has no walls to move (walls:)";
  return report.workspace->movable ? "" : report.workspace->not_movable;
}

}  // namespace hapticd::service
