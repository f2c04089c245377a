#include "service/check_command.h"

#include "drivers/transport_delay.h"
#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "service/exit_codes.h"
#include "service/result_output.h"

namespace hapticd::service {

int check_command(const ConfigOptions& options, bool json) {
  const config::Config cfg = load_config(options);
  const gate::GateReport r = gate::evaluate_gate(cfg, declared_transport_delay(cfg.device.driver));
  const std::string text = json ? gate::gate_to_json(r).dump(2) + "\n" : gate::gate_to_text(r, cfg);
  if (!write_stdout(text)) return kExitRuntimeFault;  // a verdict nobody can read is no verdict
  return r.pass ? kExitOk : kExitGateRefused;
}

}  // namespace hapticd::service
