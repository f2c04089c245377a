#include "telemetry/log_retention.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <map>

#include "base/errno_text.h"
#include "telemetry/log_path.h"

namespace hapticd::telemetry {
namespace {

// The family in deletion order: older runs' sets by the time their run ended (their newest
// file; the set number breaks ties), each from its first segment; then the current run's
// segments in order.
std::vector<FamilyFile> deletion_order(std::vector<FamilyFile> files) {
  std::map<std::uint32_t, std::int64_t> run_end;
  for (const FamilyFile& f : files) {
    std::int64_t& end = run_end[f.run];
    end = std::max(end, f.mtime_ns);
  }
  std::sort(files.begin(), files.end(), [&](const FamilyFile& a, const FamilyFile& b) {
    const bool a_current = a.run == 0, b_current = b.run == 0;
    if (a_current != b_current) return b_current;  // older runs before the current one
    if (a.run != b.run) {
      const std::int64_t ea = run_end[a.run], eb = run_end[b.run];
      return ea != eb ? ea < eb : a.run < b.run;
    }
    return a.part < b.part;
  });
  return files;
}

}  // namespace

RetentionResult enforce_retention(const std::string& path, const std::string& keep,
                                  std::uint64_t max_total, std::uint64_t reserve) {
  RetentionResult result;
  std::vector<FamilyFile> files = list_log_family(path);
  std::uint64_t others = 0;
  for (const FamilyFile& f : files) {
    result.family_bytes += f.bytes;
    if (f.path != keep) others += f.bytes;
  }
  if (max_total == 0) return result;
  for (const FamilyFile& f : deletion_order(std::move(files))) {
    if (others + reserve <= max_total) break;
    if (f.path == keep) continue;
    if (::unlink(f.path.c_str()) != 0 && errno != ENOENT) {
      result.errors.push_back(f.path + ": cannot delete: " + base::errno_text(errno));
      continue;
    }
    others -= f.bytes;
    result.family_bytes -= f.bytes;
    result.bytes += f.bytes;
    result.deleted.push_back(f.path);
  }
  return result;
}

}  // namespace hapticd::telemetry
