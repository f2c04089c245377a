#include "telemetry/log_path.h"

#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <set>
#include <string_view>

#include "base/errno_text.h"

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
constexpr std::uint32_t kMaxKept = 1000;
constexpr std::string_view kPart = ".part";

// A decimal number as this code writes them: 1-9 digits, no leading zero, not 0.
bool parse_index(std::string_view s, std::uint32_t& out) {
  if (s.empty() || s.size() > 9 || s[0] == '0') return false;
  std::uint32_t v = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + static_cast<std::uint32_t>(c - '0');
  }
  out = v;
  return true;
}

// "" | ".partK" (K >= 2) | ".N" | ".N.partK": what may follow the log's own name.
bool parse_suffix(std::string_view s, std::uint32_t& run, std::uint32_t& part) {
  run = 0;
  part = 1;
  if (s.empty()) return true;
  if (s[0] != '.') return false;
  s.remove_prefix(1);
  if (s.starts_with(kPart.substr(1))) {  // "partK"
    return parse_index(s.substr(kPart.size() - 1), part) && part >= 2;
  }
  const auto dot = s.find('.');
  if (!parse_index(s.substr(0, dot), run)) return false;
  if (dot == std::string_view::npos) return true;
  const std::string_view rest = s.substr(dot);
  return rest.starts_with(kPart) && parse_index(rest.substr(kPart.size()), part) && part >= 2;
}

struct Entry {
  FamilyFile file;
  mode_t mode = 0;
};

void split(const std::string& path, std::string& dir, std::string& base) {
  const auto slash = path.rfind('/');
  dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  base = slash == std::string::npos ? path : path.substr(slash + 1);
}

// Every directory entry whose name is `path` plus a family suffix, whatever it is (lstat).
// A directory that does not exist holds no family: whoever then opens `path` says so.
std::vector<Entry> scan_family(const std::string& path) {
  std::string dir, base;
  split(path, dir, base);
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr && errno == ENOENT) return {};
  if (d == nullptr) {
    throw std::runtime_error(dir + ": cannot list the tick logs: " + base::errno_text(errno));
  }
  std::vector<Entry> out;
  const std::string prefix = path.substr(0, path.size() - base.size());
  while (const dirent* e = ::readdir(d)) {
    const std::string_view name(e->d_name);
    Entry entry;
    if (base.empty() || !name.starts_with(base) ||
        !parse_suffix(name.substr(base.size()), entry.file.run, entry.file.part)) {
      continue;
    }
    struct stat st {};
    if (::fstatat(::dirfd(d), e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0) continue;  // gone
    entry.file.path = prefix + std::string(name);
    entry.file.bytes = static_cast<std::uint64_t>(st.st_size);
    entry.file.mtime_ns =
        static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec;
    entry.mode = st.st_mode;
    out.push_back(std::move(entry));
  }
  ::closedir(d);
  return out;
}

}  // namespace

std::string segment_path(const std::string& set, std::uint32_t index) {
  return index <= 1 ? set : set + std::string(kPart) + std::to_string(index);
}

std::vector<FamilyFile> list_log_family(const std::string& path) {
  std::vector<FamilyFile> out;
  for (Entry& e : scan_family(path)) {
    if (S_ISREG(e.mode)) out.push_back(std::move(e.file));
  }
  return out;
}

std::vector<FamilyFile> list_log_set(const std::string& set) {
  std::vector<FamilyFile> out;
  for (Entry& e : scan_family(set)) {
    if (S_ISREG(e.mode) && e.file.run == 0) out.push_back(std::move(e.file));
  }
  std::sort(out.begin(), out.end(),
            [](const FamilyFile& a, const FamilyFile& b) { return a.part < b.part; });
  return out;
}

std::string keep_previous_log(const std::string& path) {
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0 && errno != ENOENT) {
    throw std::runtime_error(path +
                             ": cannot inspect the tick log path: " + base::errno_text(errno));
  }
  std::vector<FamilyFile> current;
  std::set<std::uint32_t> taken;
  for (const Entry& e : scan_family(path)) {
    if (e.file.run != 0) {
      taken.insert(e.file.run);
    } else if (!S_ISREG(e.mode)) {
      throw LogPathError(e.file.path + ": is " + kind_of(e.mode) +
                         "; a tick log is only written to a regular file (nothing was moved)");
    } else {
      current.push_back(e.file);
    }
  }
  if (current.empty()) return "";
  std::sort(current.begin(), current.end(),
            [](const FamilyFile& a, const FamilyFile& b) { return a.part < b.part; });
  for (std::uint32_t n = 1; n <= kMaxKept; ++n) {
    if (taken.count(n) != 0) continue;
    const std::string kept = path + "." + std::to_string(n);
    std::size_t moved = 0;
    for (; moved < current.size(); ++moved) {
      const std::string to = segment_path(kept, current[moved].part);
      // RENAME_NOREPLACE: an older log is never overwritten, even in a race.
      if (renameat2(AT_FDCWD, current[moved].path.c_str(), AT_FDCWD, to.c_str(),
                    RENAME_NOREPLACE) == 0) {
        continue;
      }
      if (errno == EEXIST && moved == 0) break;  // taken since the scan: try the next N
      throw std::runtime_error(path + ": cannot keep the previous tick log " + current[moved].path +
                               " as " + to + ": " + base::errno_text(errno));
    }
    if (moved == current.size()) return kept;
  }
  throw std::runtime_error(path + ": cannot keep the previous tick log: " + path + ".1 to " + path +
                           "." + std::to_string(kMaxKept) + " all exist; move old logs away");
}

}  // namespace hapticd::telemetry
