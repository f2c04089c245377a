// Where a new tick log goes, what happens to the logs already there, and which files belong
// to one log. Only regular files are ever moved or listed, and nothing is ever moved onto
// another log: the previous log of a run that faulted is what a person reads next. Not
// RT-safe.
//
// Names. A run's log is a set of segments: the first is PATH, the next ones PATH.part2,
// PATH.part3, ... (LogWriter rolls to a new one at telemetry.max_segment_mb). When a new run
// starts, the previous set moves to the first free PATH.N as a whole (PATH.N, PATH.N.part2,
// ...). The family of PATH is all of these: the current set and every kept set. Retention may
// delete a set's first segments, so a set can start at PATH.part3 (or PATH.N.part3).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticd::telemetry {

// PATH (or one of its segments) exists and is not a regular file (a device node, a
// directory, a symlink, a FIFO...): nothing was moved. what() names the path and what is there.
class LogPathError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The file name of segment `index` (1-based) of the set named `set`: `set` for 1, else
// set + ".part" + index.
std::string segment_path(const std::string& set, std::uint32_t index);

// One regular file of a log's family.
struct FamilyFile {
  std::string path;
  std::uint32_t run = 0;   // 0: the current set (PATH...), N: the kept set PATH.N
  std::uint32_t part = 1;  // segment index: 1 for the set's own name, K for .partK
  std::uint64_t bytes = 0;
  std::int64_t mtime_ns = 0;  // last modification
};

// Every regular file of the family of `path` in its directory, in no particular order.
// Anything else with a family name (a symlink, a directory) is left out; a directory that does
// not exist has none. Throws std::runtime_error "DIR: cannot list the tick logs: REASON" when
// the directory exists but cannot be read.
std::vector<FamilyFile> list_log_family(const std::string& path);

// The segments of the set named `set` that exist, as regular files, in segment order (the set
// name first if it exists, then .part2, .part3, ...). Throws std::runtime_error as
// list_log_family does.
std::vector<FamilyFile> list_log_set(const std::string& set);

// Makes `path` free for a new log. The set at PATH (PATH and its PATH.partK, whichever of
// them exist) is renamed to the first free PATH.N (N = 1, 2, ...; a PATH.N or any PATH.N.partK
// already there makes N taken, and nothing is ever replaced) and that name is returned; ""
// when nothing was there (or the directory does not exist: opening PATH then says so). Throws
// LogPathError when PATH or a PATH.partK is not a regular file (nothing moved),
// std::runtime_error when the directory cannot be read or a rename fails.
std::string keep_previous_log(const std::string& path);

}  // namespace hapticd::telemetry
