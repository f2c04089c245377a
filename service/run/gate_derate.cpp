#include "service/run/gate_derate.h"

#include <cstdio>
#include <filesystem>
#include <string>

#include "gate/number_format.h"
#include "service/config_source.h"

namespace hapticd::service {

std::optional<std::pair<double, double>> derate_stiffness(config::Config& cfg,
                                                          int device_delay_samples,
                                                          gate::GateReport& report) {
  if (report.pass || cfg.safety.gate != config::GateMode::kDerate) return std::nullopt;
  const analysis::StiffnessLimit& limit = report.passivity.max_stiffness;
  if (report.passivity.passive || limit.kind != analysis::StiffnessLimit::Kind::kBounded ||
      !(limit.value < cfg.wall.stiffness)) {
    return std::nullopt;  // the stiffness is not what fails, or no stiffness passes
  }
  // Through the loader, as a --set would: the same validation, and an effective YAML that
  // holds the stiffness that runs to the last bit (%.17g round-trips a double).
  char k[40];
  std::snprintf(k, sizeof k, "%.17g", limit.value);
  const std::string base = std::filesystem::path(cfg.source_name).parent_path().string();
  config::Config next =
      load_config_text_checked(cfg.effective_yaml, cfg.source_name, base.empty() ? "." : base,
                               {std::string("wall.stiffness=") + k});
  gate::GateReport derated = gate::evaluate_gate(next, device_delay_samples);
  if (!derated.pass) return std::nullopt;
  const double configured = cfg.wall.stiffness;
  cfg.wall.stiffness = next.wall.stiffness;
  cfg.effective_yaml = "# safety.gate: derate ran wall.stiffness at " + std::string(k) +
                       " N/m (configured " + gate::format_number(configured, 17) + ")\n" +
                       next.effective_yaml;
  report = std::move(derated);
  return std::make_pair(configured, cfg.wall.stiffness);
}

bool gate_allows(const gate::GateReport& report, const config::Config& cfg) {
  return report.pass || cfg.safety.gate == config::GateMode::kWarn;
}

}  // namespace hapticd::service
