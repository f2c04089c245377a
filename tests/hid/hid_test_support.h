// Loading the example configurations for the HID tests.
#pragma once

#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "config/config_loader.h"
#include "drivers/hid/hid_settings.h"
#include "wiring/registry.h"

namespace hapticd::drivers::hid::testing {

inline config::Config load_example(const char* name, const std::vector<std::string>& sets = {}) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/config/" + name;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> o;
  for (const std::string& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), path, o, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

inline std::shared_ptr<const HidSettings> settings_of(const config::Config& c) {
  return std::dynamic_pointer_cast<const HidSettings>(c.device.settings);
}

}  // namespace hapticd::drivers::hid::testing
