#include "service/commands/verify_command.h"

#include <nlohmann/json.hpp>
#include <sstream>

#include "config/config_loader.h"
#include "gate/number_format.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "verify/passivity_sweep.h"
#include "wiring/registry.h"

namespace hapticd::service {

int verify_command(const ConfigOptions& options, bool json) {
  const config::Config cfg = load_config(options);
  require_one_joint(cfg, "verify");
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
                     {"device_damping", cfg.device.damping},
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
