// `hapticd replay LOG [--config OTHER] [--set ...] [--out CSV] [--json]`: the log's positions
// through its own configuration's controller (the forces must come back bit for bit) and,
// with --config, through OTHER's: its gate verdict and a side-by-side summary. The log is read
// across its segments.
#pragma once

#include <string>

#include "service/config_source.h"

namespace hapticd::service {

struct ReplayOptions {
  std::string log_path;
  ConfigOptions other;   // other.path "" and no --set: no what-if
  std::string out_path;  // CSV of the force series; "" for none
  bool json = false;
};

// Exit codes: 0 the log's forces were reproduced bit for bit; 1 they were not (or the results
// could not be written); 2 an unreadable log or a bad configuration; 3 OTHER's gate fails.
int replay_command(const ReplayOptions& options);

}  // namespace hapticd::service
