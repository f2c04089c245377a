// The replay operator's trajectory: the positions of a tick log, one per sample period,
// imposed on the simulated device (device.sim.operator kind replay).
#pragma once

#include <vector>

#include "config/config.h"

namespace hapticd::sim {

// Not RT-safe. Throws config::ConfigError naming device.sim.operator.log when the log cannot
// be read, was recorded at another rate, is empty, or has a hole in its time base (dropped
// records, a damaged stretch, missed periods); a log cut short is replayed up to its cut,
// with a warning.
std::vector<double> load_replay_positions(const config::Config& cfg);

}  // namespace hapticd::sim
