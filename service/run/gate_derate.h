// safety.gate: derate. A gate that fails only because the wall is too stiff for the device
// runs at the largest stiffness that passes (the gate's own max_stiffness) instead of
// refusing, and says so: in the events, the run summary and the configuration the tick log
// records (so `hapticd replay` rebuilds the law that ran).
#pragma once

#include <optional>
#include <utility>

#include "config/config.h"
#include "gate/gate.h"

namespace hapticd::service {

// Not RT-safe. With safety.gate: derate and a report that fails, sets wall.stiffness (and
// the effective YAML) to the largest K that passes and re-runs the gate into `report`.
// Returns {configured K, K that runs} when it did; nothing when the gate passed, the mode is
// not derate, or no lower stiffness makes it pass (then cfg and report are unchanged and the
// gate refuses as under enforce). Walls over a workspace (several joints) are not derated: the
// report's reasons then say so.
std::optional<std::pair<double, double>> derate_stiffness(config::Config& cfg,
                                                          int device_delay_samples,
                                                          gate::GateReport& report);

// Whether a gate report lets output be enabled under cfg's safety.gate (after any derating).
bool gate_allows(const gate::GateReport& report, const config::Config& cfg);

}  // namespace hapticd::service
