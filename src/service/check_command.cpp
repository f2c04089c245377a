#include "service/check_command.h"

#include "drivers/registry.h"
#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "service/exit_codes.h"
#include "service/result_output.h"

namespace hapticd::service {

int check_command(const ConfigOptions& options, bool json) {
  const config::Config cfg = load_config(options);
  // The delay the driver declares from its own settings: the one `run` and `verify` use.
  const drivers::DriverEntry& driver = drivers::find_driver(cfg.device.driver);
  const int delay = driver.declared_delay(cfg);
  const gate::GateReport r = gate::evaluate_gate(cfg, delay);
  // What the driver adds about its own transport (e.g. the CAN bus load).
  const std::vector<std::string> notes =
      driver.notes != nullptr ? driver.notes(cfg) : std::vector<std::string>{};
  std::string text;
  if (json) {
    nlohmann::json j = gate::gate_to_json(r);
    j["driver"] = cfg.device.driver;
    j["driver_notes"] = notes;
    text = j.dump(2) + "\n";
  } else {
    text = gate::gate_to_text(r, cfg);
    for (const std::string& line : notes) text += line + "\n";
  }
  if (!write_stdout(text)) return kExitRuntimeFault;  // a verdict nobody can read is no verdict
  return r.pass ? kExitOk : kExitGateRefused;
}

}  // namespace hapticd::service
