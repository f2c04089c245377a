// `hapticd curves`: the gate's analysis as curves, one JSON object for tools/hapticd-plot (the
// numbers are the project's own: the plots never recompute them). The Z-width of the
// configured device with the configured point, measured points of the passivity bound on the
// simulated loop (`verify`'s measurement), and the Nyquist plot of the oscillation check's L.
#pragma once

#include "service/config_source.h"

namespace hapticd::service {

// `measure`: also place measured points (a few seconds of simulation). Exit 0, or 2 for bad
// input.
int curves_command(const ConfigOptions& options, bool measure);

}  // namespace hapticd::service
