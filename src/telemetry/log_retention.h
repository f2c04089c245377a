// The retention cap of a log's family (log_path.h): which files go when the tick logs would
// take more than telemetry.max_total_mb. The LogWriter calls it when it opens a log and at
// every roll to a new segment, from its own thread; the RT thread never waits for it. Not
// RT-safe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hapticd::telemetry {

struct RetentionResult {
  std::vector<std::string> deleted;  // in the order they were deleted
  std::uint64_t bytes = 0;           // what they held
  std::uint64_t family_bytes = 0;    // the family's size afterwards, `keep` included
  // Files that could not be deleted, "PATH: cannot delete: REASON"; the cap is then not met.
  std::vector<std::string> errors;
};

// Deletes the oldest regular files of the family of `path` until the family, without `keep`
// (the segment being written, never deleted), plus `reserve` (the room that segment may still
// grow by) is at most `max_total` bytes. Oldest means: the kept sets of earlier runs first
// (PATH.N, by the time of their newest file, each from its first segment on), then this run's
// own segments from the first on. `max_total` 0 deletes nothing. Throws std::runtime_error
// when the directory cannot be listed.
RetentionResult enforce_retention(const std::string& path, const std::string& keep,
                                  std::uint64_t max_total, std::uint64_t reserve);

}  // namespace hapticd::telemetry
