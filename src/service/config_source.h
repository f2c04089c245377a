// The options every config-taking sub-command shares, and loading them into a Config.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"

namespace hapticd::service {

struct ConfigOptions {
  std::string path;               // empty: the embedded config/sim.yaml
  std::vector<std::string> sets;  // raw --set arguments, "key.path=value"
};

// Loads and validates, derived quantities included (control::check_derived_quantities).
// Throws config::ConfigError (exit code 2) with every problem found.
config::Config load_config(const ConfigOptions& options);

}  // namespace hapticd::service
