#include "service/commands/check_command.h"

#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "gate/number_format.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#include "service/run/gate_derate.h"
#include "service/run/run_summary.h"
#include "wiring/registry.h"

namespace hapticd::service {
namespace {

constexpr const char* kDesignHint =
    "hint: `hapticd design-coupling` (same --config and --set) designs a virtual coupling C(z) "
    "that makes this wall pass at this rate and device damping, verified by this gate, and "
    "says what it costs in transparency";

}  // namespace

int check_command(const ConfigOptions& options, bool json) {
  const config::Config cfg = load_config(options);
  // The delay the driver declares from its own settings: the one `run` and `verify` use.
  const wiring::DriverEntry& driver = wiring::find_driver(cfg.device.driver);
  const int delay = driver.declared_delay(cfg);
  const gate::GateReport r = gate::evaluate_gate(cfg, delay);
  // What `run` would do under safety.gate: derate (the verdict stays the configured wall's).
  config::Config derated_cfg = cfg;
  gate::GateReport derated_report = r;
  const auto derated = derate_stiffness(derated_cfg, delay, derated_report);
  // What the driver adds about its own transport (e.g. the CAN bus load).
  const std::vector<std::string> notes =
      driver.notes != nullptr ? driver.notes(cfg) : std::vector<std::string>{};
  // A designed coupling answers the one joint's wall the passivity bound or the coupling check
  // refuses; design-coupling designs for that wall, not for the walls of several axes.
  const bool hint =
      !r.workspace && (!r.passivity.passive || (r.coupling.present && !r.coupling.admissible));
  std::string text;
  if (json) {
    nlohmann::json j = gate::gate_to_json(r);
    j["driver"] = cfg.device.driver;
    j["driver_notes"] = notes;
    if (hint) j["design_coupling"] = kDesignHint;
    derated_to_json(derated, j);
    text = j.dump(2) + "\n";
  } else {
    text = gate::gate_to_text(r, cfg);
    for (const std::string& line : notes) text += line + "\n";
    if (hint) text += std::string(kDesignHint) + "\n";
    for (const Derating& d : derated) {
      text += "safety.gate: derate: `run` would run " + d.key + " at " +
              gate::format_number(d.ran, 10) + " N/m, the largest that passes\n";
    }
    if (derated.empty() && derated_report.reasons.size() > r.reasons.size()) {
      text += derated_report.reasons.back() + "\n";  // why derate would not help
    }
  }
  if (!write_stdout(text)) return kExitRuntimeFault;  // a verdict nobody can read is no verdict
  return r.pass ? kExitOk : kExitGateRefused;
}

}  // namespace hapticd::service
