// The shipped config/gpio.yaml, as text and loaded with the test's overrides.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config/config_loader.h"
#include "wiring/registry.h"

namespace hapticd::drivers::gpio {

inline std::string gpio_example() {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/gpio.yaml");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline config::Config load_gpio_example(const std::vector<std::string>& sets) {
  std::vector<config::Override> o;
  for (const auto& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(gpio_example(), "gpio.yaml", o, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

}  // namespace hapticd::drivers::gpio
