// The startup gate (docs/math.md): the analysis of the system that will actually run — the
// configured wall and coupling, the configured delay plus the driver's declared delay, T, b,
// eta and margin — and a verdict with the numbers a person needs to fix a failure.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "analysis/passivity.h"
#include "config/config.h"
#include "gate/workspace_gate.h"

namespace hapticd::gate {

struct PassivityReport {
  double required_damping = 0.0;   // b_req (N s/m), +inf when no damping suffices
  double available_damping = 0.0;  // (1 - passivity_margin) b: the most b_req may be
  double margin = 0.0;             // achieved: (b - b_req) / b, the fraction b may shrink by
  double worst_frequency_hz = 0.0;
  bool passive = false;  // b_req <= available_damping
  analysis::StiffnessLimit max_stiffness;
  std::string note;  // why b_req is infinite, if it is
};

struct OscillationReport {
  bool applicable = false;
  std::string note;
  bool tsai_colgate = false;
  bool tsypkin = false;
  double tsai_colgate_margin = 0.0;
  double tsypkin_margin = 0.0;
  double worst_frequency_hz = 0.0;
};

struct CouplingReport {
  bool present = false;
  bool admissible = false;
  bool dspr = false;
  double dspr_min_real = 0.0;
  double transparency_gamma = 0.0;  // +inf when H - E is unbounded
  double transparency_frequency_hz = 0.0;
  std::string note;
};

struct GateReport {
  double sample_period_s = 0.0;
  int wall_delay_samples = 0;
  int device_delay_samples = 0;
  int delay_samples = 0;  // the total the analysis used
  double device_damping = 0.0;
  double static_stiffness = 0.0;  // H(1): what a steady push feels (N/m)
  PassivityReport passivity;
  OscillationReport oscillation;
  CouplingReport coupling;
  // A device with several task axes: its walls over the workspace, in place of the one joint's
  // passivity, oscillation and coupling above (which are then not analysed).
  std::optional<WorkspaceReport> workspace;
  bool pass = false;
  std::vector<std::string> reasons;   // why it fails, with the numbers to fix it
  std::vector<std::string> warnings;  // true statements that do not fail the gate
};

// Not RT-safe. Pure function of its inputs.
GateReport evaluate_gate(const config::Config& cfg, int device_delay_samples);

}  // namespace hapticd::gate
