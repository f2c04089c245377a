// `hapticd verify`: the passivity bound confirmed by measurement on the sim loop.
#pragma once

#include "service/config_source.h"

namespace hapticd::service {

// Prints the comparison (or one JSON object); 0 when measurement and analysis agree to
// 1e-3, 1 when they do not.
int verify_command(const ConfigOptions& config, bool json);

}  // namespace hapticd::service
