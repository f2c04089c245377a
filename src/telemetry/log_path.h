// Where a new tick log goes, and what happens to a file already there. Only a regular file
// is ever moved aside, and never onto another log: the previous log of a run that faulted is
// what a person reads next. Not RT-safe.
#pragma once

#include <stdexcept>
#include <string>

namespace hapticd::telemetry {

// PATH exists and is not a regular file (a device node, a directory, a symlink, a FIFO...):
// nothing was moved. what() names the path and what is there.
class LogPathError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Makes `path` free for a new log. A regular file there is renamed to the first free
// PATH.N (N = 1, 2, ...; an existing PATH.N is never replaced) and that name is returned;
// "" when nothing was there. Throws LogPathError for anything that is not a regular file,
// std::runtime_error when the rename fails.
std::string keep_previous_log(const std::string& path);

}  // namespace hapticd::telemetry
