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

// The same for text already read (a live reload's): `source` names it in messages and
// `base_dir` resolves its relative paths; `sets` are applied as --set arguments.
config::Config load_config_text_checked(const std::string& text, const std::string& source,
                                        const std::string& base_dir,
                                        const std::vector<std::string>& sets = {});

// Throws config::ConfigError (exit code 2) naming device.kinematics when it describes several
// joints: `command` works on one joint's wall (verify, curves, design-coupling, identify), and
// the loop and its measurements for several axes are not built yet (docs/kinematics.md).
void require_one_joint(const config::Config& cfg, const std::string& command);

// A configuration file's text. Throws config::ConfigError "PATH: cannot read: REASON".
std::string read_config_file(const std::string& path);

}  // namespace hapticd::service
