#include "service/run/gate_derate.h"

#include <cstdio>
#include <string>

#include "config/config_loader.h"
#include "gate/number_format.h"

namespace hapticd::service {

std::optional<std::pair<double, double>> derate_stiffness(config::Config& cfg,
                                                          int device_delay_samples,
                                                          gate::GateReport& report) {
  if (report.pass || cfg.safety.gate != config::GateMode::kDerate) return std::nullopt;
  if (report.workspace) {
    // Walls over a workspace are not derated: each has its own largest K in the report, and
    // walls acting together bound them jointly, so which to lower is the user's choice. Said,
    // so that a refusal under derate is not taken for a derating that found nothing to pass.
    report.reasons.push_back(
        "safety.gate: derate lowers the stiffness of one joint's wall; walls on a device of "
        "several joints are not derated: set each failing wall's stiffness at most to its "
        "largest passing K above, then check again");
    return std::nullopt;
  }
  const analysis::StiffnessLimit& limit = report.passivity.max_stiffness;
  if (report.passivity.passive || limit.kind != analysis::StiffnessLimit::Kind::kBounded ||
      !(limit.value < cfg.wall.stiffness)) {
    return std::nullopt;  // the stiffness is not what fails, or no stiffness passes
  }
  // The typed value changes; the gate runs again on it. The recorded document gets the same
  // value to the last bit (%.17g round-trips a double), so `replay` rebuilds the law that ran.
  config::Config next = cfg;
  next.wall.stiffness = limit.value;
  gate::GateReport derated = gate::evaluate_gate(next, device_delay_samples);
  if (!derated.pass) return std::nullopt;
  char k[40];
  std::snprintf(k, sizeof k, "%.17g", limit.value);
  const double configured = cfg.wall.stiffness;
  cfg.effective_yaml = "# safety.gate: derate ran wall.stiffness at " + std::string(k) +
                       " N/m (configured " + gate::format_number(configured, 17) + ")\n" +
                       config::with_setting(cfg.effective_yaml, {"wall.stiffness", k, {}});
  cfg.wall.stiffness = limit.value;
  report = std::move(derated);
  return std::make_pair(configured, cfg.wall.stiffness);
}

bool gate_allows(const gate::GateReport& report, const config::Config& cfg) {
  return report.pass || cfg.safety.gate == config::GateMode::kWarn;
}

}  // namespace hapticd::service
