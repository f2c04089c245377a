// Log rotation as a user meets it: a run under a small cap rolls its log into segments and
// deletes the oldest, the summary says so, and `hapticd export` reads what is left across the
// segments in order; caps that cannot work are refused with the key.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "process.h"
#include "telemetry/log_path.h"
#include "telemetry/log_set.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

TEST(CliRotation, ARunUnderASmallCapKeepsItsNewestSegmentsAndExportReadsThemInOrder) {
  const std::string log = temp_path("rotated.hlog"), sum = temp_path("rotated.json");
  // 60000 ticks of 200 bytes are 12 MB: twelve segments of 1 MB, of which the 3 MB cap keeps two.
  const ProcessResult r =
      run_process({hapticd_binary(), "run", "--duration", "60", "--log", log, "--summary-json", sum,
                   "--set", "loop.clock=freerun", "--set", "telemetry.max_segment_mb=1", "--set",
                   "telemetry.max_total_mb=3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = json::parse(read_file(sum));
  EXPECT_GE(s["log_segments"].get<int>(), 6) << s.dump();
  EXPECT_GE(s["log_files_deleted"].get<int>(), 3) << s.dump();
  EXPECT_TRUE(has(r.out, "segments")) << r.out;
  EXPECT_TRUE(has(r.err, "retention deleted")) << r.err;

  std::uint64_t bytes = 0;
  for (const auto& f : telemetry::list_log_family(log)) {
    EXPECT_LE(f.bytes, 1u << 20) << f.path;
    bytes += f.bytes;
  }
  EXPECT_LE(bytes, 3u << 20);
  EXPECT_FALSE(std::filesystem::exists(log)) << "the first segment was the oldest";

  const telemetry::LogSet set = telemetry::read_log_set(log);
  ASSERT_GE(set.segments.size(), 2u);
  const auto& records = set.contents.records;
  ASSERT_FALSE(records.empty());
  EXPECT_EQ(records.back().tick, 59999u);
  for (std::size_t i = 1; i < records.size(); ++i) {
    ASSERT_EQ(records[i].tick, records[i - 1].tick + 1) << "in order, none missing";
  }

  const std::string csv = temp_path("rotated.csv");
  const ProcessResult e = run_process({hapticd_binary(), "export", log, "--out", csv});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_TRUE(has(e.err, std::to_string(set.segments.size()) + " segments")) << e.err;
  std::istringstream rows(read_file(csv));
  std::string line, last;
  std::size_t n = 0;
  std::getline(rows, line);  // the header
  std::string first;
  while (std::getline(rows, line)) {
    if (n++ == 0) first = line;
    last = line;
  }
  EXPECT_EQ(n, records.size());
  EXPECT_EQ(first.substr(0, first.find(',')), std::to_string(records.front().tick));
  EXPECT_EQ(last.substr(0, last.find(',')), "59999");
}

TEST(CliRotation, CapsThatCannotWorkAreRefusedWithTheKey) {
  const ProcessResult small =
      run_process({hapticd_binary(), "check", "--set", "telemetry.max_total_mb=100"});
  EXPECT_EQ(small.exit_code, 2);
  EXPECT_TRUE(has(small.err,
                  "telemetry.max_total_mb: max_total_mb 100 is less than twice max_segment_mb 64"))
      << small.err;
  const ProcessResult endless =
      run_process({hapticd_binary(), "check", "--set", "telemetry.max_segment_mb=0"});
  EXPECT_EQ(endless.exit_code, 2);
  EXPECT_TRUE(has(endless.err, "telemetry.max_segment_mb: max_segment_mb 0 with max_total_mb 1024"))
      << endless.err;
  const ProcessResult off =
      run_process({hapticd_binary(), "check", "--set", "telemetry.max_segment_mb=0", "--set",
                   "telemetry.max_total_mb=0"});
  EXPECT_EQ(off.exit_code, 0) << "no rotation and no cap: one file, kept whole\n" << off.err;
}

}  // namespace
}  // namespace hapticd::testing
