#include "service/check_command.h"

#include <iostream>

#include "drivers/transport_delay.h"
#include "gate/gate.h"
#include "gate/gate_report_format.h"
#include "service/exit_codes.h"

namespace hapticd::service {

int check_command(const ConfigOptions& options, bool json) {
  const config::Config cfg = load_config(options);
  const gate::GateReport r = gate::evaluate_gate(cfg, declared_transport_delay(cfg.device.driver));
  if (json) {
    std::cout << gate::gate_to_json(r).dump(2) << "\n";
  } else {
    std::cout << gate::gate_to_text(r, cfg);
  }
  return r.pass ? kExitOk : kExitGateRefused;
}

}  // namespace hapticd::service
