// safety.gate: derate. A gate that fails only because a wall is too stiff for the device runs
// at the largest stiffness that passes (the gate's own max_stiffness) instead of refusing, and
// says so: in the events, the run summary and the configuration the tick log records (so
// `hapticd replay` rebuilds the law that ran). Walls over a workspace (several joints) are each
// lowered to their own largest passing K, and the gate must then pass them acting together.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"
#include "gate/gate.h"

namespace hapticd::service {

// One stiffness derate lowered: `wall.stiffness`, or `walls[i].stiffness` of several joints.
struct Derating {
  std::string key;
  std::size_t wall = 0;     // i of walls[i] (0 for wall.stiffness)
  double configured = 0.0;  // N/m
  double ran = 0.0;         // N/m
};

// Not RT-safe. With safety.gate: derate and a report that fails, sets each failing wall's
// stiffness (and the effective YAML) to the largest K that passes it and re-runs the gate into
// `report`. Returns what it lowered; nothing when the gate passed, the mode is not derate, or
// the lowered walls still fail (then cfg and report are unchanged, the gate refuses as under
// enforce, and for walls the report's reasons say why derating did not help).
std::vector<Derating> derate_stiffness(config::Config& cfg, int device_delay_samples,
                                       gate::GateReport& report);

// Whether a gate report lets output be enabled under cfg's safety.gate (after any derating).
bool gate_allows(const gate::GateReport& report, const config::Config& cfg);

// Why a client may not move the walls the report judged (gate/workspace_gate.h, movable), with
// the gate's numbers; "" when it may.
std::string why_not_movable(const gate::GateReport& report);

}  // namespace hapticd::service
