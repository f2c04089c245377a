// `hapticd check`: the gate's analysis without touching hardware.
#pragma once

#include "service/config_source.h"

namespace hapticd::service {

// Prints the table (or one JSON object) and returns 0 on pass, 3 on fail.
int check_command(const ConfigOptions& config, bool json);

}  // namespace hapticd::service
