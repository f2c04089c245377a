// The clients' state block (client/state_layout.h): the daemon's writer against the client
// library's reader over a real sealed memfd. A reader gets every tick whole and in order, counts
// what it fell too far behind to read, never gets a sample half written, and can neither write
// the block nor resize it; the writer allocates nothing.
#include "telemetry/state_block.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <thread>

#include "alloc_counter.h"
#include "client/connection.h"
#include "client/state_reader.h"

namespace hapticd::telemetry {
namespace {

using client::StateReader;
using client::StateSample;

// Sample n, every field a function of n: a torn read shows as fields that disagree.
StateSample sample(std::uint64_t n) {
  StateSample s;
  s.tick = n;
  s.time_ns = static_cast<std::int64_t>(n) * 1000;
  for (int i = 0; i < 3; ++i) {
    s.q[i] = s.x[i] = static_cast<double>(n) + i;
    s.f[i] = -static_cast<double>(n);
  }
  s.wall_contact = static_cast<std::uint32_t>(n & 0xff);
  return s;
}

bool whole(const StateSample& s) {
  const StateSample want = sample(s.tick);
  return s.time_ns == want.time_ns && s.x[2] == want.x[2] && s.f[0] == want.f[0] &&
         s.q[1] == want.q[1] && s.wall_contact == want.wall_contact;
}

StateReader reader_of(const StateBlock& b) {
  return StateReader(fcntl(b.fd(), F_DUPFD_CLOEXEC, 0));
}

TEST(StateBlock, AReaderGetsEveryTickFromItsFirstLookInOrder) {
  StateBlock block(16, 1000000, 3, 3);
  StateReader r = reader_of(block);
  EXPECT_EQ(r.slots(), 16u);
  EXPECT_EQ(r.sample_period_ns(), 1000000u);
  EXPECT_EQ(r.joints(), 3u);
  StateSample s;
  EXPECT_FALSE(r.latest(s));
  EXPECT_FALSE(r.next(s));  // its first look: from here on, every tick
  for (std::uint64_t n = 0; n < 5; ++n) block.publish(sample(n));
  ASSERT_TRUE(r.latest(s));
  EXPECT_EQ(s.tick, 4u);
  for (std::uint64_t n = 0; n < 5; ++n) {
    ASSERT_TRUE(r.next(s));
    EXPECT_EQ(s.tick, n);
    EXPECT_TRUE(whole(s));
  }
  EXPECT_FALSE(r.next(s));
  StateReader late = reader_of(block);  // a reader that first looks now starts at tick 5
  EXPECT_FALSE(late.next(s));
  for (std::uint64_t n = 5; n < 9; ++n) block.publish(sample(n));
  ASSERT_TRUE(late.next(s));
  EXPECT_EQ(s.tick, 5u);
  for (std::uint64_t n = 5; n < 9; ++n) {
    ASSERT_TRUE(r.next(s));
    EXPECT_EQ(s.tick, n);
  }
  EXPECT_FALSE(r.next(s));
  EXPECT_EQ(r.missed(), 0u);
}

TEST(StateBlock, AReaderLappedByTheLoopCountsWhatItMissedAndGoesOn) {
  StateBlock block(16, 1000000, 1, 1);
  StateReader r = reader_of(block);
  StateSample s;
  EXPECT_FALSE(r.next(s));
  block.publish(sample(0));
  ASSERT_TRUE(r.next(s));
  for (std::uint64_t n = 1; n <= 40; ++n) block.publish(sample(n));  // 40 new, 16 held
  ASSERT_TRUE(r.next(s));
  EXPECT_EQ(s.tick, 25u);  // the oldest still held
  EXPECT_EQ(r.missed(), 24u);
  std::uint64_t last = s.tick;
  while (r.next(s)) last = s.tick;
  EXPECT_EQ(last, 40u);
  EXPECT_EQ(r.missed(), 24u);
  EXPECT_EQ(r.read(3, s), StateReader::Read::kMissed);
  EXPECT_EQ(r.read(41, s), StateReader::Read::kNotYet);
}

TEST(StateBlock, ARacingReaderNeverGetsAHalfWrittenSample) {
  StateBlock block(8, 1000000, 3, 3);  // a small ring: the writer laps the reader often
  std::atomic<bool> done{false};
  std::uint64_t read = 0, torn = 0, out_of_order = 0;
  std::thread reader([&] {
    StateReader r = reader_of(block);
    StateSample s;
    std::uint64_t previous = 0;
    while (!done.load(std::memory_order_acquire)) {
      while (r.next(s)) {
        ++read;
        torn += whole(s) ? 0 : 1;
        out_of_order += read > 1 && s.tick <= previous ? 1 : 0;
        previous = s.tick;
      }
    }
  });
  for (std::uint64_t n = 0; n < 200000; ++n) block.publish(sample(n));
  done.store(true, std::memory_order_release);
  reader.join();
  EXPECT_GT(read, 0u);
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(out_of_order, 0u);
}

TEST(StateBlock, ClientsCanNeitherWriteNorResizeIt) {
  StateBlock block(16, 1000000, 1, 1);
  const std::size_t bytes = client::kStateHeaderBytes + 16 * client::kStateSlotBytes;
  errno = 0;
  EXPECT_EQ(mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, block.fd(), 0), MAP_FAILED);
  EXPECT_EQ(errno, EPERM);
  EXPECT_NE(ftruncate(block.fd(), 0), 0);
  EXPECT_NE(ftruncate(block.fd(), static_cast<off_t>(2 * bytes)), 0);
  const char junk = 'x';
  EXPECT_LT(pwrite(block.fd(), &junk, 1, 0), 0);
}

TEST(StateBlock, WhatIsNoStateBlockIsRefusedByName) {
  const int fd = memfd_create("not-state", MFD_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(ftruncate(fd, 4096), 0);
  try {
    StateReader r(fd);
    FAIL() << "a block of zeros was read";
  } catch (const client::ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("not a hapticd state block"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(StateBlock(12, 1000000, 1, 1), std::invalid_argument);
}

TEST(StateBlock, PublishingAllocatesNothing) {
  StateBlock block(64, 1000000, 3, 3);
  testing::AllocationScope scope;
  for (std::uint64_t n = 0; n < 1000; ++n) block.publish(sample(n));
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(block.published(), 1000u);
}

}  // namespace
}  // namespace hapticd::telemetry
