// What the driver benchmarks share: an example configuration from config/, in freerun (the
// benchmark is the clock), with the benchmark's own overrides applied after.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config/config_loader.h"
#include "drivers/registry.h"

namespace hapticd::bench {

inline config::Config load_example(const char* name, const std::vector<std::string>& sets = {}) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/config/" + name;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> o = {config::parse_override("loop.clock=freerun")};
  for (const std::string& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), path, o, HAPTICD_SOURCE_DIR "/config",
                                  drivers::driver_schemas());
}

}  // namespace hapticd::bench
