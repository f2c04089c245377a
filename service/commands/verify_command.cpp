#include "service/commands/verify_command.h"

#include <nlohmann/json.hpp>
#include <sstream>

#include "config/config_loader.h"
#include "gate/number_format.h"
#include "gate/workspace_gate.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "verify/passivity_sweep.h"
#include "verify/workspace_verify.h"
#include "wiring/registry.h"

namespace hapticd::service {

namespace {

std::string position_mm(const kinematics::Vec3& x, int m) {
  std::string out = "(";
  for (int i = 0; i < m; ++i) out += (i ? ", " : "") + gate::format_number(x[i] * 1e3);
  return out + ") mm";
}

// A device of several joints: each wall along its normal at the configuration the gate found
// worst for it (verify/workspace_verify.h), the gate's verdict for that wall beside.
int verify_walls(const config::Config& cfg, bool as_json) {
  const int delay = wiring::find_driver(cfg.device.driver).declared_delay(cfg);
  const gate::WorkspaceReport report = gate::evaluate_workspace(cfg, delay);
  std::vector<kinematics::Vec3> worst;
  for (const gate::WallVerdict& w : report.walls) worst.push_back(w.worst_position);
  verify::WorkspaceVerifyResult r;
  try {
    r = verify::verify_workspace(cfg, delay, worst);
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError({cfg.source_name + ": " + e.what()});
  }
  const int m = kinematics::joint_count(cfg.device.kinematics);
  nlohmann::json walls = nlohmann::json::array();
  std::ostringstream os;
  using gate::format_number;
  os << "hapticd verify: " << cfg.source_name << " (each wall along its normal at its worst "
     << "configuration; an attractor along the way the device is least damped there)\n"
     << "  imposed motion           x* + d A cos(wt), A = " << format_number(r.amplitude * 1e3)
     << " mm along the least dissipating d (n . d = 1)\n"
     << "  delay                    driver " << delay << " samples + each wall's delay_samples\n";
  for (std::size_t i = 0; i < r.walls.size(); ++i) {
    const verify::WallVerify& v = r.walls[i];
    const bool gate_pass = report.walls[i].passive;
    walls.push_back({{"position", {v.position[0], v.position[1], v.position[2]}},
                     {"analytic_required_damping", v.analytic_required_damping},
                     {"measured_required_damping", v.measured_required_damping},
                     {"worst_frequency_hz", v.worst_frequency_hz},
                     {"relative_error", v.relative_error},
                     {"normal_damping", v.normal_damping},
                     {"measured_normal_damping", v.measured_normal_damping},
                     {"measured_passive", v.measured_passive},
                     {"gate_passive", gate_pass},
                     {"simulated_ticks", v.ticks},
                     {"verdict", v.agrees ? "agree" : "disagree"}});
    os << "  walls[" << i << "]                 at " << position_mm(v.position, m) << ": b_req "
       << format_number(v.analytic_required_damping, 8) << " analytic, "
       << format_number(v.measured_required_damping, 8) << " measured at "
       << format_number(v.worst_frequency_hz) << " Hz (error " << format_number(v.relative_error, 3)
       << "); b_n " << format_number(v.normal_damping) << " (measured "
       << format_number(v.measured_normal_damping)
       << "): " << (v.measured_passive ? "passive" : "ACTIVE") << " there; the gate "
       << (gate_pass ? "passes" : "refuses") << " it\n";
  }
  os << "  verdict                  " << (r.agrees ? "AGREE" : "DISAGREE") << " (tolerance "
     << format_number(verify::kVerifyTolerance) << ")\n";
  const nlohmann::json j{{"walls", walls},
                         {"amplitude", r.amplitude},
                         {"device_delay_samples", delay},
                         {"tolerance", verify::kVerifyTolerance},
                         {"verdict", r.agrees ? "agree" : "disagree"}};
  if (!write_stdout(as_json ? j.dump(2) + "\n" : os.str())) return kExitRuntimeFault;
  return r.agrees ? kExitOk : kExitRuntimeFault;
}

}  // namespace

int verify_command(const ConfigOptions& options, bool json) {
  const config::Config cfg = load_config(options);
  if (kinematics::joint_count(cfg.device.kinematics) > 1) return verify_walls(cfg, json);
  verify::VerifyResult r;
  try {
    r = verify::verify_passivity(cfg, wiring::find_driver(cfg.device.driver).declared_delay(cfg));
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError({cfg.source_name + ": " + e.what()});
  }
  std::string text;
  if (json) {
    nlohmann::json j{{"analytic_required_damping", r.analytic_required_damping},
                     {"analytic_worst_frequency_hz", r.analytic_worst_frequency_hz},
                     {"measured_required_damping", r.measured_required_damping},
                     {"relative_error", r.relative_error},
                     {"worst_frequency_hz", r.worst_frequency_hz},
                     {"delay_samples", r.delay_samples},
                     {"device_damping", cfg.device.damping[0]},
                     {"frequencies_measured", r.sweep.size()},
                     {"simulated_ticks", r.ticks},
                     {"tolerance", verify::kVerifyTolerance},
                     {"verdict", r.agrees ? "agree" : "disagree"}};
    text = j.dump(2) + "\n";
  } else {
    using gate::format_number;
    std::ostringstream os;
    os << "hapticd verify: " << cfg.source_name << "\n"
       << "  imposed motion           2A + A cos(wt) penetration, A = "
       << format_number(r.amplitude * 1e3) << " mm, constant velocity within each sample\n"
       << "  delay                    " << r.delay_samples << " samples\n"
       << "  frequencies measured     " << r.sweep.size() << " (" << r.ticks
       << " simulated ticks)\n"
       << "  analytic b_req           " << format_number(r.analytic_required_damping, 10)
       << " N s/m at " << format_number(r.analytic_worst_frequency_hz) << " Hz\n"
       << "  measured b_req           " << format_number(r.measured_required_damping, 10)
       << " N s/m at " << format_number(r.worst_frequency_hz) << " Hz\n"
       << "  relative error           " << format_number(r.relative_error, 3) << " (tolerance "
       << format_number(verify::kVerifyTolerance) << ")\n"
       << "  verdict                  " << (r.agrees ? "AGREE" : "DISAGREE") << "\n";
    text = os.str();
  }
  if (!write_stdout(text)) return kExitRuntimeFault;
  return r.agrees ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
