#include "telemetry/log_path.h"

#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>

namespace hapticd::telemetry {
namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Highest N tried before giving up: a directory with a thousand old logs needs a person.
constexpr int kMaxKept = 1000;

}  // namespace

std::string keep_previous_log(const std::string& path) {
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return "";
    throw std::runtime_error(path + ": cannot inspect the tick log path: " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    throw LogPathError(path + ": is " + kind_of(st.st_mode) +
                       "; a tick log is only written to a regular file (nothing was moved)");
  }
  for (int n = 1; n <= kMaxKept; ++n) {
    const std::string kept = path + "." + std::to_string(n);
    // RENAME_NOREPLACE: an older log at PATH.N is never overwritten, even in a race.
    if (renameat2(AT_FDCWD, path.c_str(), AT_FDCWD, kept.c_str(), RENAME_NOREPLACE) == 0) {
      return kept;
    }
    if (errno != EEXIST) {
      throw std::runtime_error(path + ": cannot keep the previous tick log as " + kept + ": " +
                               std::strerror(errno));
    }
  }
  throw std::runtime_error(path + ": cannot keep the previous tick log: " + path + ".1 to " + path +
                           "." + std::to_string(kMaxKept) + " all exist; move old logs away");
}

}  // namespace hapticd::telemetry
