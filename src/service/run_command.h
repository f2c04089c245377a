// `hapticd run`: the main job. Gate, enable, loop until the duration ends, a signal or a
// fault; then zero force, disable output, flush the log, summarise.
#pragma once

#include <optional>
#include <string>

#include "service/config_source.h"

namespace hapticd::service {

struct RunOptions {
  ConfigOptions config;
  std::optional<double> duration_s;  // none: until SIGINT/SIGTERM
  std::string log_path;              // overrides telemetry.log
  std::string summary_json_path;
};

// Returns the process exit code (DESIGN.md §9).
int run_command(const RunOptions& options);

}  // namespace hapticd::service
