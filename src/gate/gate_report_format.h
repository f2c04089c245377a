// The two renderings of a GateReport: the JSON object of `hapticd check --json` (and the
// `gate` member of the run summary) and the short table a person reads.
#pragma once

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "gate/gate.h"

namespace hapticd::gate {

// Keys of `hapticd check --json` (docs/operations.md); null where a value does not apply (or is
// infinite).
nlohmann::json gate_to_json(const GateReport& r);

std::string gate_to_text(const GateReport& r, const config::Config& cfg);

// A number for JSON, or null where it is not finite (JSON has no infinity).
nlohmann::json finite_or_null(double v);

// What a largest passing stiffness that is not a bound says: unbounded, or none at all ("" for
// a bound).
std::string stiffness_note(const analysis::StiffnessLimit& lim);

// The `workspace` member and the table's rows for a device with several task axes
// (workspace_report_format.cpp).
nlohmann::json workspace_to_json(const WorkspaceReport& w);
void workspace_rows(const WorkspaceReport& w, const config::Config& cfg, std::ostream& os);

}  // namespace hapticd::gate
