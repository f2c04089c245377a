// `hapticd export`: a tick log as CSV, one row per record, for plotting and analysis.
#pragma once

#include <string>

namespace hapticd::service {

// Writes CSV to `out_path` (stdout when empty). Returns the exit code: 0, or 2 for a file
// that is not a readable tick log. A log cut short exports its complete blocks and says so.
int export_command(const std::string& log_path, const std::string& out_path);

}  // namespace hapticd::service
