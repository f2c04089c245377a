// The reader on good logs, logs cut short at every byte, corrupted logs and non-logs.
#include "telemetry/log_reader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "older_log.h"
#include "telemetry/log_writer.h"
#include "telemetry_test_util.h"

namespace hapticd::telemetry {
namespace {

using test::make_records;
using test::records_identical;
using test::sample_header;

std::string format_error(std::span<const std::byte> bytes) {
  try {
    read_log_bytes(bytes, "mem.htl");
  } catch (const LogFormatError& e) {
    return e.what();
  }
  return "no error";
}

// A log of 5 blocks of 3 records, laid out by hand from the documented sizes.
struct FiveBlockLog {
  static constexpr std::size_t kBlocks = 5, kPerBlock = 3;
  test::TempDir dir;
  std::string path = dir.file("five.htl");
  LogHeader header = sample_header();
  std::vector<TickRecord> records = make_records(1000, kBlocks* kPerBlock);
  std::size_t header_size = 44 + header.config_text.size();
  std::size_t block_bytes = 28 + kPerBlock * kRecordSize;
  std::vector<std::byte> bytes;

  FiveBlockLog() {
    write_log_file(path, header, records, kPerBlock);
    bytes = test::read_bytes(path);
  }
  std::vector<TickRecord> first_blocks(std::size_t k) const {
    return {records.begin(), records.begin() + static_cast<std::ptrdiff_t>(k * kPerBlock)};
  }
  std::size_t block_start(std::size_t k) const { return header_size + k * block_bytes; }
};

TEST(LogReader, ReadsBackWhatWasWritten) {
  FiveBlockLog log;
  ASSERT_EQ(log.bytes.size(), log.block_start(5));
  const LogContents c = read_log(log.path);
  EXPECT_TRUE(records_identical(c.records, log.records));
  EXPECT_EQ(c.header.config_text, log.header.config_text);
  EXPECT_EQ(c.header.sample_period_s, log.header.sample_period_s);
  EXPECT_EQ(c.header.start_unix_ns, log.header.start_unix_ns);
  EXPECT_EQ(c.header.clock_mode, kClockModeFreerun);
  EXPECT_EQ(c.complete_blocks, 5u);
  EXPECT_EQ(c.dropped_records, 0u);
  EXPECT_EQ(c.trailing_bytes_ignored, 0u);
  EXPECT_EQ(c.trailing_reason, "");
}

TEST(LogReader, LogWithoutBlocksIsValidAndEmpty) {
  test::TempDir dir;
  LogHeader header = sample_header();
  header.config_text.clear();
  write_log_file(dir.file("empty.htl"), header, {});
  const LogContents c = read_log(dir.file("empty.htl"));
  EXPECT_TRUE(c.records.empty());
  EXPECT_EQ(c.header.config_text, "");
  EXPECT_EQ(c.complete_blocks, 0u);
  EXPECT_EQ(c.trailing_reason, "");
}

TEST(LogReader, CutAtEveryByteKeepsTheCompleteBlocksBeforeIt) {
  FiveBlockLog log;
  for (std::size_t cut = 0; cut <= log.bytes.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    const auto prefix = std::span(log.bytes).first(cut);
    if (cut < log.header_size) {
      ASSERT_EQ(format_error(prefix), "mem.htl: truncated header");
      continue;
    }
    const std::size_t complete = (cut - log.header_size) / log.block_bytes;
    const std::size_t good_end = log.block_start(complete);
    const LogContents c = read_log_bytes(prefix, "mem.htl");
    ASSERT_TRUE(records_identical(c.records, log.first_blocks(complete)));
    ASSERT_EQ(c.complete_blocks, complete);
    ASSERT_EQ(c.trailing_bytes_ignored, cut - good_end);
    if (cut == good_end) {
      ASSERT_EQ(c.trailing_reason, "");
    } else {
      ASSERT_EQ(c.trailing_reason,
                "incomplete block at byte " + std::to_string(good_end) + " (log cut short)");
    }
  }
}

TEST(LogReader, CutFilesOnDiskReadTheSameWay) {
  FiveBlockLog log;
  const std::string cut_path = log.dir.file("cut.htl");
  // A cut inside the header, at a block boundary, inside a block header, inside records.
  for (std::size_t cut :
       {std::size_t{5}, log.block_start(2), log.block_start(3) + 10, log.block_start(4) + 100}) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    test::write_bytes(cut_path, std::span(log.bytes).first(cut));
    if (cut < log.header_size) {
      try {
        read_log(cut_path);
        ADD_FAILURE() << "expected LogFormatError";
      } catch (const LogFormatError& e) {
        EXPECT_EQ(std::string(e.what()), cut_path + ": truncated header");
      }
      continue;
    }
    const LogContents c = read_log(cut_path);
    const std::size_t complete = (cut - log.header_size) / log.block_bytes;
    EXPECT_TRUE(records_identical(c.records, log.first_blocks(complete)));
    EXPECT_EQ(c.trailing_bytes_ignored, cut - log.block_start(complete));
  }
}

// Issue 7: one flipped bit in a block used to cost every later intact block of the log.
TEST(LogReader, FlippedByteSkipsOnlyTheDamagedBlock) {
  FiveBlockLog log;
  const std::size_t damaged = 2;
  const std::size_t start = log.block_start(damaged);
  const std::string where = "at byte " + std::to_string(start);
  std::vector<TickRecord> survivors = log.first_blocks(damaged);
  survivors.insert(survivors.end(), log.records.begin() + (damaged + 1) * FiveBlockLog::kPerBlock,
                   log.records.end());
  for (std::size_t i = 0; i < log.block_bytes; ++i) {
    SCOPED_TRACE("flipped byte " + std::to_string(i) + " of block 2");
    std::vector<std::byte> bytes = log.bytes;
    bytes[start + i] ^= std::byte{0xff};
    const LogContents c = read_log_bytes(bytes, "mem.htl");
    ASSERT_TRUE(records_identical(c.records, survivors));
    ASSERT_EQ(c.complete_blocks, FiveBlockLog::kBlocks - 1);
    ASSERT_EQ(c.trailing_reason, "");
    ASSERT_EQ(c.trailing_bytes_ignored, 0u);
    ASSERT_EQ(c.skipped.size(), 1u);
    ASSERT_EQ(c.skipped[0].offset, start);
    ASSERT_EQ(c.skipped[0].bytes, log.block_bytes);
    const std::string& why = c.skipped[0].reason;
    if (i < 4) {
      ASSERT_EQ(why, "bad block magic " + where);
    } else if (i < 6) {  // the record count grows past the end of the file
      ASSERT_EQ(why, "incomplete block " + where + " (log cut short)");
    } else if (i < 8) {  // the record count exceeds kMaxBlockRecords
      ASSERT_EQ(why.rfind("corrupt block header " + where + " (record count ", 0), 0u) << why;
    } else {
      ASSERT_EQ(why, "CRC mismatch in block " + where);
    }
  }
}

TEST(LogReader, DamageInTheLastBlockEndsTheReadThere) {
  FiveBlockLog log;
  const std::size_t last = FiveBlockLog::kBlocks - 1;
  std::vector<std::byte> bytes = log.bytes;
  bytes[log.block_start(last) + 40] ^= std::byte{0x01};
  const LogContents c = read_log_bytes(bytes, "mem.htl");
  EXPECT_TRUE(records_identical(c.records, log.first_blocks(last)));
  EXPECT_TRUE(c.skipped.empty());
  EXPECT_EQ(c.trailing_reason,
            "CRC mismatch in block at byte " + std::to_string(log.block_start(last)));
  EXPECT_EQ(c.trailing_bytes_ignored, log.block_bytes);
}

// Issue 7 (UB under the sanitizers): memcmp(nullptr, magic, 0) on an empty file.
TEST(LogReader, EmptyInputIsATruncatedHeader) {
  const std::vector<std::byte> none;
  EXPECT_EQ(format_error(none), "mem.htl: truncated header");
}

// Issue 7 (UB under the sanitizers): memcpy(nullptr, ..., 0) when the first block is a loss
// marker, which the daemon writes itself when the disk fills right after the header.
TEST(LogReader, ALogWhoseFirstBlockIsALossMarkerReads) {
  const LogHeader header = sample_header();
  std::vector<std::byte> bytes = encode_file_header(header);
  std::vector<std::byte> marker(block_size(0));
  ASSERT_EQ(encode_block(marker, 0, 42, {}), block_size(0));
  bytes.insert(bytes.end(), marker.begin(), marker.end());
  const LogContents c = read_log_bytes(bytes, "mem.htl");
  EXPECT_TRUE(c.records.empty());
  EXPECT_EQ(c.complete_blocks, 1u);
  EXPECT_EQ(c.dropped_records, 42u);
  EXPECT_EQ(c.trailing_reason, "");
}

TEST(LogReader, ReadsVersion1LogsWithTheNewFieldsZero) {
  const std::vector<TickRecord> rs = make_records(40, 6);
  const LogContents c =
      read_log_bytes(hapticd::testing::older_log(1, sample_header(), rs), "v1.htl");
  EXPECT_EQ(c.version, 1u);
  ASSERT_EQ(c.records.size(), rs.size());
  for (std::size_t i = 0; i < rs.size(); ++i) {
    EXPECT_EQ(std::memcmp(&c.records[i], &rs[i], 72), 0) << i;
    EXPECT_EQ(c.records[i].sample_time_ns, 0);
    EXPECT_EQ(c.records[i].sequence, 0u);
    EXPECT_EQ(c.records[i].fault_code, 0u);
    EXPECT_EQ(c.records[i].observer_energy_j, 0.0);
  }
  EXPECT_EQ(c.trailing_reason, "");
}

TEST(LogReader, ReadsVersion2LogsWithTheObserverZero) {
  const std::vector<TickRecord> rs = make_records(40, 6);
  const LogContents c =
      read_log_bytes(hapticd::testing::older_log(2, sample_header(), rs), "v2.htl");
  EXPECT_EQ(c.version, 2u);
  ASSERT_EQ(c.records.size(), rs.size());
  for (std::size_t i = 0; i < rs.size(); ++i) {
    EXPECT_EQ(std::memcmp(&c.records[i], &rs[i], 96), 0) << i;
    EXPECT_NE(rs[i].observer_energy_j, 0.0);  // make_records fills it: the zero is the reader's
    EXPECT_EQ(c.records[i].observer_energy_j, 0.0);
    EXPECT_EQ(c.records[i].passivity_damping, 0.0);
  }
  EXPECT_EQ(c.trailing_reason, "");
}

TEST(LogReader, ReadsVersion3LogsWithTheJointsZero) {
  std::vector<TickRecord> rs = make_records(40, 6);
  for (TickRecord& r : rs) {
    r.joints = 3;  // what a version 4 record would carry, and version 3's cannot
    r.task_position[2] = 0.1;
  }
  const LogContents c =
      read_log_bytes(hapticd::testing::older_log(3, sample_header(), rs), "v3.htl");
  EXPECT_EQ(c.version, 3u);
  ASSERT_EQ(c.records.size(), rs.size());
  for (std::size_t i = 0; i < rs.size(); ++i) {
    EXPECT_EQ(std::memcmp(&c.records[i], &rs[i], 112), 0) << i;
    EXPECT_EQ(c.records[i].joints, 0u);
    EXPECT_EQ(c.records[i].task_position[2], 0.0);
  }
  EXPECT_EQ(c.trailing_reason, "");
}

TEST(LogReader, RejectsFilesThatAreNotTickLogs) {
  FiveBlockLog log;
  auto damaged = [&](std::size_t offset, std::byte value) {
    std::vector<std::byte> b = log.bytes;
    b[offset] = value;
    return format_error(b);
  };
  EXPECT_EQ(damaged(0, std::byte{'h'}), "mem.htl: not a hapticd tick log (bad magic)");
  EXPECT_EQ(damaged(8, std::byte{6}), "mem.htl: unsupported log version 6");
  EXPECT_EQ(damaged(41, std::byte{'#'}), "mem.htl: header CRC mismatch");   // config text
  EXPECT_EQ(damaged(17, std::byte{0x11}), "mem.htl: header CRC mismatch");  // sample period
  EXPECT_EQ(damaged(39, std::byte{0x7f}),
            "mem.htl: corrupt header (configuration length " +
                std::to_string(0x7f000000u + log.header.config_text.size()) + ")");

  const std::string text = "position,force\n0.1,2.0\n";
  EXPECT_EQ(format_error(std::as_bytes(std::span(text))),
            "mem.htl: not a hapticd tick log (bad magic)");
}

TEST(LogReader, ReportsUnreadableFilesWithTheirPath) {
  test::TempDir dir;
  const std::string missing = dir.file("missing.htl");
  try {
    read_log(missing);
    FAIL() << "expected LogFormatError";
  } catch (const LogFormatError& e) {
    EXPECT_EQ(std::string(e.what()), missing + ": cannot read: No such file or directory");
  }
  const std::string a_dir = dir.file("");
  EXPECT_THROW(read_log(a_dir), LogFormatError);
}

}  // namespace
}  // namespace hapticd::telemetry
