// LogWriter: what the writer thread puts on disk, how ring overflow and disk errors show up
// in the log, and its lifecycle.
#include "telemetry/log_writer.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>

#include <array>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.h"
#include "telemetry/log_reader.h"
#include "telemetry_test_util.h"

namespace hapticd::telemetry {
namespace {

using std::chrono::milliseconds;
using test::make_record;
using test::make_records;
using test::records_identical;
using test::sample_header;

// The block headers of a log the reader accepted completely, in file order.
std::vector<BlockHeader> block_headers(const std::vector<std::byte>& bytes,
                                       std::size_t config_len) {
  std::vector<BlockHeader> out;
  for (std::size_t at = file_header_size(config_len); at < bytes.size();) {
    out.push_back(decode_block_header(std::span(bytes).subspan(at)));
    at += block_size(out.back().record_count);
  }
  return out;
}

TEST(LogWriter, ThreadWritesEveryRecordWithTheHeader) {
  test::TempDir dir;
  const std::string path = dir.file("round.htl");
  SpscRing<TickRecord> ring(64);
  const LogHeader header = sample_header();
  const std::vector<TickRecord> records = make_records(0, 5000);
  LogWriter writer(path, header, ring, 7, milliseconds(1));
  EXPECT_EQ(writer.path(), path);
  writer.start();
  for (const TickRecord& r : records) {
    // The producer's own view of the fill level is exact enough to never drop here.
    while (ring.size_approx() >= ring.capacity()) std::this_thread::yield();
    ASSERT_TRUE(ring.try_push(r));
  }
  writer.stop();

  EXPECT_EQ(writer.records_written(), records.size());
  EXPECT_EQ(writer.records_dropped(), 0u);
  EXPECT_EQ(writer.io_errors(), 0u);
  EXPECT_EQ(writer.last_error(), "");
  const LogContents c = read_log(path);
  EXPECT_TRUE(records_identical(c.records, records));
  EXPECT_EQ(c.header.config_text, header.config_text);
  EXPECT_EQ(c.header.sample_period_s, header.sample_period_s);
  EXPECT_EQ(c.header.start_unix_ns, header.start_unix_ns);
  EXPECT_EQ(c.header.clock_mode, header.clock_mode);
  EXPECT_EQ(c.dropped_records, 0u);
  EXPECT_EQ(c.trailing_reason, "");
  for (const BlockHeader& h : block_headers(test::read_bytes(path), header.config_text.size())) {
    EXPECT_GE(h.record_count, 1u);
    EXPECT_LE(h.record_count, 7u);
  }
}

TEST(LogWriter, WritesTheSameBytesAsWriteLogFile) {
  test::TempDir dir;
  SpscRing<TickRecord> ring(32);
  const std::vector<TickRecord> records = make_records(500, 15);
  for (const TickRecord& r : records) ASSERT_TRUE(ring.try_push(r));
  LogWriter writer(dir.file("thread.htl"), sample_header(), ring, 3);
  writer.start();
  writer.stop();
  write_log_file(dir.file("direct.htl"), sample_header(), records, 3);
  EXPECT_EQ(test::read_bytes(dir.file("thread.htl")), test::read_bytes(dir.file("direct.htl")));
}

TEST(LogWriter, FullBlocksFlushMakesTheFileDependOnTheRecordsAlone) {
  // A producer that trickles records across many poll periods: with kEveryPoll the block cuts
  // follow the timing; with kFullBlocks they fall every 7 records whatever the timing.
  test::TempDir dir;
  SpscRing<TickRecord> ring(64);
  const std::vector<TickRecord> records = make_records(0, 40);
  LogWriter writer(dir.file("full.htl"), sample_header(), ring, 7, milliseconds(1),
                   LogWriter::Flush::kFullBlocks);
  writer.start();
  for (const TickRecord& r : records) {
    ASSERT_TRUE(ring.try_push(r));
    std::this_thread::sleep_for(milliseconds(2));  // more than one poll between records
  }
  writer.stop();
  write_log_file(dir.file("direct.htl"), sample_header(), records, 7);
  EXPECT_EQ(test::read_bytes(dir.file("full.htl")), test::read_bytes(dir.file("direct.htl")));
}

TEST(LogWriter, RingOverflowIsMarkedWhereTheTicksAreMissing) {
  test::TempDir dir;
  const std::string path = dir.file("overflow.htl");
  constexpr std::uint64_t kTicks = 200'000;
  SpscRing<TickRecord> ring(8);
  const LogHeader header = sample_header();
  // Blocks of 3 do not tile the 8 slots, so a pop can reach across a gap: the ring must split it.
  LogWriter writer(path, header, ring, 3, milliseconds(1));
  writer.start();
  for (std::uint64_t t = 0; t < kTicks; ++t) ring.try_push(make_record(t));  // never waits
  writer.stop();

  ASSERT_GT(ring.dropped(), 0u) << "the producer never outran an 8-slot ring";
  const LogContents c = read_log(path);
  ASSERT_EQ(c.trailing_reason, "");
  EXPECT_EQ(c.dropped_records, ring.dropped());
  EXPECT_EQ(writer.records_dropped(), ring.dropped());
  EXPECT_EQ(c.records.size() + c.dropped_records, kTicks);
  EXPECT_EQ(writer.records_written(), c.records.size());

  // Each marker sits exactly at its gap: the first tick of a block is the tick after the
  // previous block's last one plus the block's dropped_before, and blocks have no gaps.
  std::uint64_t next = 0;
  std::size_t r = 0;
  for (const BlockHeader& h : block_headers(test::read_bytes(path), header.config_text.size())) {
    if (h.record_count == 0) {
      EXPECT_EQ(h.first_tick, next);
      next += h.dropped_before;
      continue;
    }
    ASSERT_EQ(c.records[r].tick, next + h.dropped_before) << "block at record " << r;
    ASSERT_EQ(h.first_tick, c.records[r].tick);
    for (std::uint32_t i = 0; i < h.record_count; ++i, ++r) {
      ASSERT_TRUE(test::same_bytes(c.records[r], make_record(c.records[r].tick)));
      if (i > 0) {
        ASSERT_EQ(c.records[r].tick, c.records[r - 1].tick + 1);
      }
    }
    next = c.records[r - 1].tick + 1;
  }
  EXPECT_EQ(next, kTicks);
}

TEST(LogWriter, DropsAfterTheLastRecordBecomeALossMarkerAtStop) {
  test::TempDir dir;
  const std::string path = dir.file("trailing.htl");
  SpscRing<TickRecord> ring(4);
  LogWriter writer(path, sample_header(), ring);
  for (std::uint64_t t = 0; t < 10; ++t) ring.try_push(make_record(t));  // 4..9 dropped
  writer.stop();  // never started: stop() drains on this thread

  const LogContents c = read_log(path);
  EXPECT_TRUE(records_identical(c.records, make_records(0, 4)));
  EXPECT_EQ(c.dropped_records, 6u);
  EXPECT_EQ(c.complete_blocks, 2u);
  const auto blocks = block_headers(test::read_bytes(path), sample_header().config_text.size());
  ASSERT_EQ(blocks.size(), 2u);
  EXPECT_EQ(blocks[1].record_count, 0u);
  EXPECT_EQ(blocks[1].first_tick, 4u);
  EXPECT_EQ(blocks[1].dropped_before, 6u);
}

void ignore_signal(int) {}

// Lowers RLIMIT_FSIZE so writes past `bytes` fail with EFBIG (SIGXFSZ caught, not fatal).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    struct sigaction ignore {};
    ignore.sa_handler = ignore_signal;
    sigaction(SIGXFSZ, &ignore, &old_action_);
    getrlimit(RLIMIT_FSIZE, &old_limit_);
    rlimit limit = old_limit_;
    limit.rlim_cur = bytes;
    ok_ = setrlimit(RLIMIT_FSIZE, &limit) == 0;
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_limit_);
    sigaction(SIGXFSZ, &old_action_, nullptr);
  }
  bool ok() const { return ok_; }

 private:
  struct sigaction old_action_ {};
  rlimit old_limit_{};
  bool ok_ = false;
};

TEST(LogWriter, DiskErrorsAreCountedAndTheLogStaysReadable) {
  test::TempDir dir;
  const std::string path = dir.file("full.htl");
  SpscRing<TickRecord> ring(64);
  const LogHeader header = sample_header();
  LogWriter writer(path, header, ring, 4);
  for (std::uint64_t t = 0; t < 12; ++t) ASSERT_TRUE(ring.try_push(make_record(t)));
  const std::size_t header_size = file_header_size(header.config_text.size());
  {
    // Room for the header, one block of 4 and 100 more bytes: the second and third blocks
    // are cut mid-write; the 28-byte loss marker written at stop still fits.
    FileSizeLimit limit(header_size + block_size(4) + 100);
    if (!limit.ok()) GTEST_SKIP() << "cannot lower RLIMIT_FSIZE";
    writer.stop();
  }
  EXPECT_EQ(writer.io_errors(), 2u);
  EXPECT_EQ(writer.last_error(), path + ": write failed: " + std::strerror(EFBIG));
  EXPECT_EQ(writer.records_written(), 4u);
  EXPECT_EQ(writer.records_lost(), 8u) << "records the disk refused";
  EXPECT_EQ(writer.records_dropped(), 0u)
      << "the ring dropped nothing: a full disk is not a full ring";

  const LogContents c = read_log(path);
  EXPECT_TRUE(records_identical(c.records, make_records(0, 4)));
  EXPECT_EQ(c.dropped_records, 8u) << "records lost to the disk are marked like ring drops";
  EXPECT_EQ(c.trailing_reason, "") << "the partial block must not be left behind";
  EXPECT_EQ(c.trailing_bytes_ignored, 0u);
  EXPECT_EQ(std::filesystem::file_size(path), header_size + block_size(4) + block_size(0));
}

TEST(LogWriter, DrainingDoesNotAllocate) {
  test::TempDir dir;
  SpscRing<TickRecord> ring(2048);
  LogWriter writer(dir.file("alloc.htl"), sample_header(), ring, 16);
  for (std::uint64_t t = 0; t < 1000; ++t) ASSERT_TRUE(ring.try_push(make_record(t)));
  {
    testing::AllocationScope scope;
    writer.stop();  // drains 63 blocks on this thread, where the counter can see them
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_EQ(writer.records_written(), 1000u);
}

TEST(LogWriter, UnwritablePathThrowsWithThePath) {
  test::TempDir dir;
  SpscRing<TickRecord> ring(8);
  const std::string path = dir.file("no-such-dir/tick.htl");
  try {
    LogWriter writer(path, sample_header(), ring);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": cannot open tick log: No such file or directory");
  }
  try {
    write_log_file(path, sample_header(), make_records(0, 3));
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": cannot open tick log: No such file or directory");
  }
}

TEST(LogWriter, RejectsBadBlockSizesBeforeTouchingTheFile) {
  test::TempDir dir;
  SpscRing<TickRecord> ring(8);
  const std::string path = dir.file("never.htl");
  EXPECT_THROW(LogWriter(path, sample_header(), ring, 0), std::invalid_argument);
  EXPECT_THROW(LogWriter(path, sample_header(), ring, kMaxBlockRecords + 1), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(LogWriter, StopIsIdempotentAndTheDestructorFlushes) {
  test::TempDir dir;
  SpscRing<TickRecord> ring(16);
  {
    LogWriter writer(dir.file("a.htl"), sample_header(), ring);
    writer.start();
    writer.start();  // no second thread
    ASSERT_TRUE(ring.try_push(make_record(1)));
    writer.stop();
    writer.stop();
    EXPECT_THROW(writer.start(), std::logic_error);
    EXPECT_EQ(writer.records_written(), 1u);
  }
  {
    LogWriter writer(dir.file("b.htl"), sample_header(), ring);
    writer.start();
    for (std::uint64_t t = 2; t < 12; ++t) ASSERT_TRUE(ring.try_push(make_record(t)));
  }  // destructor: stop()
  EXPECT_TRUE(records_identical(read_log(dir.file("a.htl")).records, make_records(1, 1)));
  EXPECT_TRUE(records_identical(read_log(dir.file("b.htl")).records, make_records(2, 10)));
}

// The log ends with the run's counters (the counters block), read back as they were; a
// counters block that does not parse is a damaged stretch the reader names, never a crash.
TEST(LogWriter, TheLogEndsWithTheRunsCounters) {
  test::TempDir dir;
  SpscRing<TickRecord> ring(16);
  std::array<base::Counter, 2> loop{{{"stale_ticks", base::CounterKind::kAnomaly, "stale"},
                                     {"contact_ticks", base::CounterKind::kCount, "contact"}}};
  loop[0].add(3);
  loop[1].add(1234567890123ull);
  {
    LogWriter writer(dir.file("c.htl"), sample_header(), ring);
    writer.set_counters([&] {
      base::CounterRegistry r;
      r.add("loop", loop);
      return r.read();
    });
    writer.start();
    for (std::uint64_t t = 0; t < 10; ++t) ASSERT_TRUE(ring.try_push(make_record(t)));
    writer.stop();
  }
  const LogContents c = read_log(dir.file("c.htl"));
  EXPECT_EQ(c.records.size(), 10u);
  EXPECT_EQ(c.trailing_reason, "");
  ASSERT_EQ(c.counters.size(), 2u);
  EXPECT_EQ(c.counters[0].source, "loop");
  EXPECT_EQ(c.counters[0].name, "stale_ticks");
  EXPECT_EQ(c.counters[0].kind, base::CounterKind::kAnomaly);
  EXPECT_EQ(c.counters[0].value, 3u);
  EXPECT_EQ(c.counters[1].value, 1234567890123ull);

  // A counters block whose text is not "SOURCE NAME KIND VALUE" lines, CRC and all intact.
  std::vector<std::byte> bytes = test::read_bytes(dir.file("c.htl"));
  const std::vector<std::byte> bad = encode_counters_block(10, "loop stale_ticks sometimes 3\n");
  bytes.insert(bytes.end(), bad.begin(), bad.end());
  const LogContents d = read_log_bytes(bytes, "bad.htl");
  EXPECT_EQ(d.records.size(), 10u);
  EXPECT_EQ(d.counters.size(), 2u) << "the intact block before it still counts";
  EXPECT_NE(d.trailing_reason.find("malformed counters block"), std::string::npos)
      << d.trailing_reason;
}

}  // namespace
}  // namespace hapticd::telemetry
