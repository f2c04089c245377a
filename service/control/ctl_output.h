// hapticctl's human output: the daemon's answers (control_protocol.h) as a few aligned lines.
// `--json` prints the answer itself instead.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace hapticd::service {

// The "status" member of a status answer.
std::string status_text(const nlohmann::json& status);
// The "reload" member of an accepted reload's answer, or the "scene" member of an accepted
// scene request's.
std::string reload_text(const nlohmann::json& reload);

}  // namespace hapticd::service
