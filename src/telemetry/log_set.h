// A run's tick log read whole across its segments (log_path.h names them): the set PATH is
// PATH, PATH.part2, PATH.part3, ...; a kept set PATH.N is PATH.N, PATH.N.part2, ... Each
// segment is a complete log with its own header; read together they are the run's log, as
// `hapticd export` and `hapticd replay` see it. Not RT-safe.
#pragma once

#include <string>
#include <vector>

#include "telemetry/log_reader.h"

namespace hapticd::telemetry {

struct LogSet {
  // The header of the first segment read (the configuration in force at its first tick);
  // the records, reloads, blocks and losses of every segment in order. A segment cut short or
  // damaged before the last one, or a missing segment between two present ones, is reported
  // in contents.skipped (its reason names the segment); the last segment's cut is
  // contents.trailing_reason.
  LogContents contents;
  std::vector<std::string> segments;  // the files read, in order
};

// Reads the set named `set`. A set whose first segments were deleted by retention starts at
// its first remaining segment. Throws LogFormatError: "SET: cannot read: No such file or
// directory" when no segment exists, a segment's own errors (read_log), and "SEGMENT: not a
// segment of the run in FIRST (WHAT differs)" or "SEGMENT: does not continue FIRST (...)" for a
// file that does not belong with the others.
LogSet read_log_set(const std::string& set);

}  // namespace hapticd::telemetry
