// Helpers of the `hapticd design-coupling` end-to-end tests: the command run with --json, and
// its coupling pasted into a configuration as --set arguments.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "process.h"

namespace hapticd::testing {

// `hapticd design-coupling --json EXTRA...`: its JSON object, with "exit_code" added. Expects
// exit 0 or 1 and a progress line on stderr per step the JSON reports.
nlohmann::json design_coupling_json(const std::vector<std::string>& extra);

// The designed coupling pasted into the configuration, as --set arguments.
std::vector<std::string> pasted_coupling(const nlohmann::json& design);

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b);

}  // namespace hapticd::testing
