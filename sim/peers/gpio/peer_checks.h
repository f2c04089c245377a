// The GPIO peers simulate the encoder device.gpio describes, with the plant of device.sim
// behind it: their resolutions must agree, or the driver would read another scale than the
// plant's. (The start count need not: like a real relative encoder, the driver's count is
// start_count plus whatever the encoder moved since configure; config/gpio.yaml sets it to
// device.sim.initial_position x counts_per_unit so the two frames coincide.)
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "config/config.h"
#include "config/config_loader.h"
#include "drivers/gpio/gpio_settings.h"

namespace hapticd::sim::gpio {

inline void check_peer_config(const config::Config& cfg, const drivers::gpio::GpioSettings& s) {
  std::vector<std::string> errors;
  const double cpu = cfg.device.sim.counts_per_unit;
  for (std::size_t j = 0; j < s.joints.size(); ++j) {
    if (cpu == std::abs(s.joints[j].counts_per_unit)) continue;
    const std::string key = s.key(j, "counts_per_unit");
    errors.push_back(cfg.locate(key) + ": " + key + ": the simulated encoder has " +
                     std::to_string(cpu) + " counts per unit (device.sim.counts_per_unit); " +
                     "the two must agree in magnitude");
  }
  if (!errors.empty()) throw config::ConfigError(errors);
}

}  // namespace hapticd::sim::gpio
