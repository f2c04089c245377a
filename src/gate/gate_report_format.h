// The two renderings of a GateReport: the JSON object of `hapticd check --json` (and the
// `gate` member of the run summary) and the short table a person reads.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "gate/gate.h"

namespace hapticd::gate {

// Keys of `hapticd check --json` (docs/operations.md); null where a value does not apply (or is
// infinite).
nlohmann::json gate_to_json(const GateReport& r);

std::string gate_to_text(const GateReport& r, const config::Config& cfg);

}  // namespace hapticd::gate
