#include "telemetry/log_set.h"

#include <sys/stat.h>

#include <optional>

#include "telemetry/log_path.h"

namespace hapticd::telemetry {
namespace {

// The segments to read, in order. The set's own name is read even when it is a symlink to a
// log (as read_log always did); a listing that fails leaves the set's name alone.
std::vector<FamilyFile> segments_of(const std::string& set) {
  std::vector<FamilyFile> files;
  try {
    files = list_log_set(set);
  } catch (const std::runtime_error&) {
    files.clear();
  }
  struct stat st {};
  const bool named = !files.empty() && files.front().part == 1;
  if (!named && (files.empty() || ::stat(set.c_str(), &st) == 0)) {
    files.insert(files.begin(), FamilyFile{set, 0, 1, 0, 0});  // read_log reports what is wrong
  }
  return files;
}

// What differs between two headers of one run's segments ("" if nothing that must agree).
std::string header_difference(const LogContents& a, const LogContents& b) {
  if (a.version != b.version) return "format version";
  if (a.header.sample_period_s != b.header.sample_period_s) return "sample period";
  if (a.header.clock_mode != b.header.clock_mode) return "clock mode";
  if (a.header.start_unix_ns != b.header.start_unix_ns) return "start time";
  return "";
}

std::optional<std::uint64_t> first_tick(const LogContents& c) {
  for (const TickRecord& r : c.records) {
    if (r.marker == kMarkerNone) return r.tick;
  }
  return std::nullopt;
}

std::optional<std::uint64_t> last_tick(const LogContents& c) {
  for (auto it = c.records.rbegin(); it != c.records.rend(); ++it) {
    if (it->marker == kMarkerNone) return it->tick;
  }
  return std::nullopt;
}

// Checks that `c` (read from `path`) belongs after what `out` holds so far.
void check_continues(const LogSet& out, const LogContents& c, const std::string& path,
                     const std::optional<std::uint64_t>& last) {
  if (const std::string what = header_difference(out.contents, c); !what.empty()) {
    throw LogFormatError(path + ": not a segment of the run in " + out.segments.front() + " (" +
                         what + " differs)");
  }
  const auto first = first_tick(c);
  if (last && first && *first <= *last) {
    throw LogFormatError(path + ": does not continue " + out.segments.back() + " (its first tick " +
                         std::to_string(*first) + " is not after tick " + std::to_string(*last) +
                         ")");
  }
}

}  // namespace

LogSet read_log_set(const std::string& set) {
  const std::vector<FamilyFile> files = segments_of(set);
  const bool several = files.size() > 1;
  LogSet out;
  LogContents& all = out.contents;
  std::optional<std::uint64_t> last;
  std::uint32_t part = 0;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::string& path = files[i].path;
    LogContents c = read_log(path);
    const auto named = [&](const std::string& why) { return several ? path + ": " + why : why; };
    if (i == 0) {
      all.header = c.header;
      all.version = c.version;
    } else {
      check_continues(out, c, path, last);
      for (std::uint32_t k = part + 1; k < files[i].part; ++k) {
        all.skipped.push_back(
            {0, 0, segment_path(set, k) + ": missing; the ticks it held are not in the log"});
      }
    }
    part = files[i].part;
    out.segments.push_back(path);
    if (const auto t = last_tick(c)) last = t;
    all.records.insert(all.records.end(), c.records.begin(), c.records.end());
    all.reloads.insert(all.reloads.end(), c.reloads.begin(), c.reloads.end());
    if (!c.counters.empty()) all.counters = std::move(c.counters);  // the run's end: the last
    all.complete_blocks += c.complete_blocks;
    all.dropped_records += c.dropped_records;
    for (SkippedRegion& s : c.skipped) all.skipped.push_back({s.offset, s.bytes, named(s.reason)});
    if (i + 1 < files.size()) {
      // A segment cut short before the last one: a damaged stretch of the set, not its end.
      if (!c.trailing_reason.empty()) {
        all.skipped.push_back({0, c.trailing_bytes_ignored, named(c.trailing_reason)});
      }
    } else {
      all.trailing_reason = c.trailing_reason.empty() ? "" : named(c.trailing_reason);
      all.trailing_bytes_ignored = c.trailing_bytes_ignored;
    }
  }
  return out;
}

}  // namespace hapticd::telemetry
