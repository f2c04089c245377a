// Config -> the Device the loop will drive. The one place that knows every driver.
#pragma once

#include <memory>
#include <vector>

#include "config/config.h"
#include "drivers/device.h"

namespace hapticd::service {

// Not RT-safe. Throws DeviceError (exit code 4) for a driver this build cannot open, and
// config::ConfigError for a replay log that does not fit the loop.
std::unique_ptr<Device> make_device(const config::Config& cfg);

// Positions of a tick log, for the replay operator. Throws config::ConfigError naming
// device.sim.operator.log when the log cannot be used.
std::vector<double> load_replay_positions(const config::Config& cfg);

}  // namespace hapticd::service
