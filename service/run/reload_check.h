// What a live reload may change while the loop runs: the wall (stiffness, damping,
// discretisation, delay, no-pull, coupling) or the walls of a device of several joints (each
// wall's point, normal and law; walls added or removed), the analysis models, the gate's
// mode, margin and the operator's shortage of passivity, and one joint's force limit.
// Everything else needs a new device, a new rate or a new loop - a restart - and a reload that
// changes it is refused with the reason.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"

namespace hapticd::service {

// Not RT-safe. One "key: why" line per change `next` makes that a reload cannot apply;
// empty when it can be applied at a tick boundary.
std::vector<std::string> reload_blockers(const config::Config& running, const config::Config& next);

}  // namespace hapticd::service
