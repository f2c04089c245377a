// Log segments and retention: the writer rolls to PATH.part2, PATH.part3, ... before a segment
// passes its cap, each segment a complete log with its own header; the retention cap deletes
// the oldest files of the family; a set is read back whole, in order, and a reload's config
// block lands in the segment of its marker and in the next segments' headers.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/time.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "telemetry/log_path.h"
#include "telemetry/log_reader.h"
#include "telemetry/log_retention.h"
#include "telemetry/log_set.h"
#include "telemetry/log_writer.h"
#include "telemetry_test_util.h"

namespace hapticd::telemetry {
namespace {

using std::chrono::milliseconds;
using test::make_records;
using test::records_identical;
using test::sample_header;

constexpr std::uint64_t kSegment = 64 * 1024;  // about 330 records of 200 bytes per segment

// Writes `records` through a LogWriter with `rotation`, in blocks of 32; the writer, stopped.
std::vector<std::string> write_rotated(const std::string& path,
                                       const std::vector<TickRecord>& records,
                                       LogWriter::Rotation rotation) {
  std::vector<std::string> events;
  rotation.on_event = [&](const std::string& e) { events.push_back(e); };
  SpscRing<TickRecord> ring(256);
  LogWriter writer(path, sample_header(), ring, 32, milliseconds(1));
  writer.set_rotation(rotation);
  writer.start();
  for (const TickRecord& r : records) {
    while (ring.size_approx() >= ring.capacity()) std::this_thread::yield();
    ring.try_push(r);
  }
  writer.stop();
  EXPECT_EQ(writer.io_errors(), 0u) << writer.last_error();
  EXPECT_EQ(writer.records_written(), records.size());
  return events;
}

std::uint64_t family_bytes(const std::string& path) {
  std::uint64_t total = 0;
  for (const FamilyFile& f : list_log_family(path)) total += f.bytes;
  return total;
}

TEST(LogRotation, EverySegmentIsACompleteLogAndTheSetReadsBackWhole) {
  test::TempDir dir;
  const std::string path = dir.file("run.hlog");
  const std::vector<TickRecord> records = make_records(0, 5000);
  const auto events = write_rotated(path, records, {kSegment, 0, {}});
  const std::vector<FamilyFile> set = list_log_set(path);
  ASSERT_GE(set.size(), 7u) << "5000 records of 200 bytes are 1 MB: 16 segments of 64 KB";
  std::vector<TickRecord> joined;
  for (std::size_t i = 0; i < set.size(); ++i) {
    EXPECT_EQ(set[i].path, segment_path(path, static_cast<std::uint32_t>(i + 1)));
    EXPECT_LE(set[i].bytes, kSegment) << set[i].path;
    const LogContents c = read_log(set[i].path);  // alone: its own header, intact blocks
    EXPECT_EQ(c.header.config_text, sample_header().config_text);
    EXPECT_TRUE(c.trailing_reason.empty()) << c.trailing_reason;
    joined.insert(joined.end(), c.records.begin(), c.records.end());
  }
  EXPECT_TRUE(records_identical(joined, records));
  EXPECT_EQ(events.size(), set.size() - 1) << "one sentence per roll";

  const LogSet whole = read_log_set(path);
  EXPECT_EQ(whole.segments.size(), set.size());
  EXPECT_TRUE(records_identical(whole.contents.records, records));
  EXPECT_TRUE(whole.contents.skipped.empty());
  EXPECT_TRUE(whole.contents.trailing_reason.empty());
}

TEST(LogRotation, RetentionKeepsTheFamilyUnderItsCapDeletingTheOldestFirst) {
  test::TempDir dir;
  const std::string path = dir.file("run.hlog");
  // An earlier run's log, kept as run.hlog.1 when this one starts, is the oldest of all.
  write_log_file(path, sample_header(), make_records(0, 100));
  EXPECT_EQ(keep_previous_log(path), path + ".1");
  const std::vector<TickRecord> records = make_records(0, 5000);
  const auto events = write_rotated(path, records, {kSegment, 4 * kSegment, {}});
  EXPECT_FALSE(std::filesystem::exists(path + ".1")) << "the older run went first";
  EXPECT_LE(family_bytes(path), 4 * kSegment);
  EXPECT_FALSE(std::filesystem::exists(path)) << "then this run's first segments";
  const LogSet left = read_log_set(path);  // starts at the first segment that is left
  ASSERT_GE(left.segments.size(), 2u);
  EXPECT_NE(left.segments.front(), path);
  const std::vector<TickRecord>& got = left.contents.records;
  ASSERT_FALSE(got.empty());
  const std::vector<TickRecord> tail(records.end() - static_cast<long>(got.size()), records.end());
  EXPECT_TRUE(records_identical(got, tail)) << "what is left is the newest, whole";
  bool said = false;
  for (const std::string& e : events)
    said = said || e.find("retention deleted") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(LogRotation, AKeptRunMovesAsAWholeSet) {
  test::TempDir dir;
  const std::string path = dir.file("run.hlog");
  const std::vector<TickRecord> records = make_records(0, 2000);
  write_rotated(path, records, {kSegment, 0, {}});
  const std::size_t parts = list_log_set(path).size();
  ASSERT_GE(parts, 3u);
  EXPECT_EQ(keep_previous_log(path), path + ".1");
  EXPECT_TRUE(list_log_set(path).empty());
  EXPECT_TRUE(std::filesystem::exists(path + ".1.part" + std::to_string(parts)));
  EXPECT_TRUE(records_identical(read_log_set(path + ".1").contents.records, records));
  // A second kept run takes the next number, never the first one's parts.
  write_rotated(path, records, {kSegment, 0, {}});
  EXPECT_EQ(keep_previous_log(path), path + ".2");
  EXPECT_TRUE(records_identical(read_log_set(path + ".2").contents.records, records));
}

TEST(LogRotation, AMissingOrForeignSegmentIsReported) {
  test::TempDir dir;
  const std::string path = dir.file("run.hlog");
  write_rotated(path, make_records(0, 3000), {kSegment, 0, {}});
  ASSERT_TRUE(std::filesystem::remove(segment_path(path, 3)));
  const LogSet gap = read_log_set(path);
  ASSERT_FALSE(gap.contents.skipped.empty());
  EXPECT_EQ(gap.contents.skipped.front().reason,
            segment_path(path, 3) + ": missing; the ticks it held are not in the log");
  // A log of another run put where part 3 was: refused by name.
  LogHeader other = sample_header();
  other.start_unix_ns += 1;
  write_log_file(segment_path(path, 3), other, make_records(100000, 10));
  try {
    read_log_set(path);
    ADD_FAILURE() << "a foreign segment was accepted";
  } catch (const LogFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("run.hlog.part3: not a segment of the run in"),
              std::string::npos)
        << e.what();
  }
}

TEST(LogRotation, AReloadsConfigurationGoesIntoTheNextSegmentsHeaders) {
  test::TempDir dir;
  const std::string path = dir.file("run.hlog");
  std::vector<TickRecord> records = make_records(0, 3000);
  records.insert(records.begin() + 200, make_records(200, 1).front());
  records[200].marker = kMarkerReloadAccepted;  // the reload governs from tick 200
  SpscRing<TickRecord> ring(256);
  LogWriter writer(path, sample_header(), ring, 32, milliseconds(1));
  writer.set_rotation({kSegment, 0, {}});
  writer.queue_config_change("wall:\n  stiffness: 1234\n");
  writer.start();
  for (const TickRecord& r : records) {
    while (ring.size_approx() >= ring.capacity()) std::this_thread::yield();
    ring.try_push(r);
  }
  writer.stop();
  const LogSet set = read_log_set(path);
  ASSERT_EQ(set.contents.reloads.size(), 1u);
  EXPECT_EQ(set.contents.reloads[0].first_tick, 200u);
  EXPECT_EQ(set.contents.reloads[0].config_text, "wall:\n  stiffness: 1234\n");
  EXPECT_EQ(read_log(path).header.config_text, sample_header().config_text);
  EXPECT_EQ(read_log(segment_path(path, 2)).header.config_text, "wall:\n  stiffness: 1234\n");
  EXPECT_TRUE(records_identical(set.contents.records, records));
}

TEST(LogRetention, OlderRunsGoByTheirAgeEachFromItsFirstSegment) {
  test::TempDir dir;
  const std::string path = dir.file("r.hlog");
  const auto make = [&](const std::string& name, std::size_t kb, int age_s) {
    test::write_bytes(dir.file(name), std::vector<std::byte>(kb * 1024));
    const timeval t[2] = {{time(nullptr) - age_s, 0}, {time(nullptr) - age_s, 0}};
    utimes(dir.file(name).c_str(), t);
  };
  make("r.hlog.2", 10, 300);        // the oldest run
  make("r.hlog.2.part2", 10, 290);  //
  make("r.hlog.1", 10, 100);        // a newer run, though numbered lower
  make("r.hlog", 10, 50);           // this run's first segment
  make("r.hlog.part2", 10, 0);      // the segment being written
  make("r.hlog.other", 10, 400);    // not of the family: never touched
  const RetentionResult r = enforce_retention(path, path + ".part2", 25 * 1024, 10 * 1024);
  EXPECT_EQ(r.deleted, (std::vector<std::string>{path + ".2", path + ".2.part2", path + ".1"}));
  EXPECT_TRUE(r.errors.empty());
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::exists(path + ".other"));
  EXPECT_EQ(enforce_retention(path, path + ".part2", 0, 0).deleted.size(), 0u) << "0: no cap";
}

}  // namespace
}  // namespace hapticd::telemetry
