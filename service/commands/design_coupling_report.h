// What `hapticd design-coupling` prints: the design, the gate's verdict on it, both
// transparency measures beside the configured coupling's and the bare wall's, the curve
// tools/hapticd-plot draws, and the `wall.coupling` YAML to paste (text), or all of it as one
// JSON object.
#pragma once

#include <string>

#include "analysis/coupling_design.h"
#include "config/config.h"
#include "gate/gate.h"
#include "service/commands/design_coupling_command.h"

namespace hapticd::service {

struct DesignReport {
  const config::Config& cfg;
  const DesignCouplingOptions& options;
  int device_delay = 0;
  analysis::CouplingSpec spec;
  analysis::CouplingDesign design;
  std::string solver;
  gate::GateReport gate;     // of cfg with the designed coupling
  bool gate_passed = false;  // passes, and Theorem 1 holds by the gate's exact DSPR check
  // The wall passes the gate without a coupling: nothing is designed (every coupling Theorem 1
  // admits would only make the wall yield under a steady push, H(1) = 0).
  bool not_needed = false;
  gate::GateReport bare_gate;  // of cfg without its coupling, when not_needed

  bool designed() const {
    return design.status == analysis::CouplingDesign::Status::kDesigned && gate_passed;
  }
  std::string failure() const;  // why nothing is offered (or, not_needed, why none is)
};

std::string design_report_text(const DesignReport& r);
std::string design_report_json(const DesignReport& r);

}  // namespace hapticd::service
