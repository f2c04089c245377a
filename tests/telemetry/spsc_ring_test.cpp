// SpscRing: order, wrap-around, drop accounting, allocation-freedom, and a two-thread stress.
#include "telemetry/spsc_ring.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "alloc_counter.h"
#include "telemetry/tick_record.h"
#include "telemetry_test_util.h"

namespace hapticd::telemetry {
namespace {

using test::make_record;
using test::same_bytes;

TEST(SpscRing, RejectsCapacityBelowTwo) {
  EXPECT_THROW(SpscRing<TickRecord>(0), std::invalid_argument);
  EXPECT_THROW(SpscRing<TickRecord>(1), std::invalid_argument);
  SpscRing<TickRecord> ring(2);
  EXPECT_EQ(ring.capacity(), 2u);
}

TEST(SpscRing, KeepsFifoOrderAcrossManyWrapArounds) {
  // 3 is not a power of two: the index wrap must not rely on masking.
  SpscRing<std::uint64_t> ring(3);
  std::uint64_t next_in = 0;
  std::uint64_t next_out = 0;
  std::uint64_t out[3] = {};
  for (int lap = 0; lap < 100; ++lap) {
    ASSERT_TRUE(ring.try_push(next_in++));
    ASSERT_TRUE(ring.try_push(next_in++));
    ASSERT_EQ(ring.size_approx(), 2u);
    ASSERT_EQ(ring.pop_many(out, 1), 1u);
    ASSERT_EQ(out[0], next_out++);
    ASSERT_EQ(ring.pop_many(out, 3), 1u);
    ASSERT_EQ(out[0], next_out++);
    ASSERT_EQ(ring.size_approx(), 0u);
  }
  // Fill to the brim at an arbitrary offset and read it all back in one call.
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(ring.try_push(next_in++));
  EXPECT_EQ(ring.size_approx(), 3u);
  ASSERT_EQ(ring.pop_many(out, 3), 3u);
  for (std::uint64_t v : out) EXPECT_EQ(v, next_out++);
  EXPECT_EQ(ring.pop_many(out, 3), 0u);
  EXPECT_EQ(ring.dropped(), 0u);
}

TEST(SpscRing, FullRingDropsAndCountsInsteadOfBlocking) {
  SpscRing<TickRecord> ring(4);
  for (std::uint64_t t = 0; t < 10; ++t) EXPECT_EQ(ring.try_push(make_record(t)), t < 4) << t;
  EXPECT_EQ(ring.dropped(), 6u);
  EXPECT_EQ(ring.size_approx(), 4u);

  std::vector<TickRecord> out(8);
  ASSERT_EQ(ring.pop_many(out.data(), out.size()), 4u);
  for (std::uint64_t t = 0; t < 4; ++t) EXPECT_TRUE(same_bytes(out[t], make_record(t)));
  // Space is back: pushes succeed again and the drop count stays as it was.
  EXPECT_TRUE(ring.try_push(make_record(10)));
  EXPECT_EQ(ring.dropped(), 6u);
}

TEST(SpscRing, PopRunReportsExactlyWhereRecordsWereDropped) {
  SpscRing<std::uint64_t> ring(4);
  std::uint64_t out[10] = {};
  std::uint64_t dropped_before = 99;
  for (std::uint64_t v = 0; v < 6; ++v) ring.try_push(v);  // 4 and 5 dropped
  ASSERT_EQ(ring.pop_run(out, 2, dropped_before), 2u);     // 0 1
  EXPECT_EQ(dropped_before, 0u);
  ring.try_push(6);
  ring.try_push(7);
  ring.try_push(8);                                      // dropped: ring holds 2 3 6 7
  ASSERT_EQ(ring.pop_run(out, 10, dropped_before), 2u);  // 2 3, the run ends before the gap
  EXPECT_EQ(out[0], 2u);
  EXPECT_EQ(out[1], 3u);
  EXPECT_EQ(dropped_before, 0u);
  EXPECT_EQ(ring.take_trailing_drops(), 0u) << "records still waiting carry the drops";
  ASSERT_EQ(ring.pop_run(out, 10, dropped_before), 2u);  // 6 7
  EXPECT_EQ(out[0], 6u);
  EXPECT_EQ(dropped_before, 2u);  // 4 and 5
  EXPECT_EQ(ring.pop_run(out, 10, dropped_before), 0u);
  EXPECT_EQ(dropped_before, 0u);
  EXPECT_EQ(ring.take_trailing_drops(), 1u);  // 8
  EXPECT_EQ(ring.take_trailing_drops(), 0u);  // reported once only
  ring.try_push(9);
  ASSERT_EQ(ring.pop_run(out, 10, dropped_before), 1u);
  EXPECT_EQ(out[0], 9u);
  EXPECT_EQ(dropped_before, 0u) << "8 was already reported as trailing";
  EXPECT_EQ(ring.dropped(), 3u);
}

TEST(SpscRing, PushAndPopDoNotAllocate) {
  {  // The counter must be able to see an allocation, or the zero below proves nothing.
    testing::AllocationScope control;
    auto p = std::make_unique<int>(1);
    ASSERT_GE(control.count(), 1u);
  }
  SpscRing<TickRecord> ring(1024);
  std::vector<TickRecord> out(256);
  const TickRecord rec = make_record(7);
  std::uint64_t dropped_before = 0;
  testing::AllocationScope scope;
  for (int i = 0; i < 100'000; ++i) {
    ring.try_push(rec);  // fills, then mostly drops: both paths are exercised
    if (i % 4096 == 0) ring.pop_many(out.data(), out.size());
    if (i % 4096 == 2048) ring.pop_run(out.data(), out.size(), dropped_before);
  }
  ring.take_trailing_drops();
  EXPECT_EQ(scope.count(), 0u) << (testing::malloc_is_counted() ? "malloc and new counted"
                                                                : "operator new counted");
  EXPECT_GT(ring.dropped(), 0u);
}

constexpr std::uint64_t kStressRecords = 1'000'000;

// Producer pushes ticks 0..N-1 into a tiny ring as fast as it can; returns when done.
void produce(SpscRing<TickRecord>& ring, std::atomic<bool>& done) {
  for (std::uint64_t t = 0; t < kStressRecords; ++t) ring.try_push(make_record(t));
  done.store(true, std::memory_order_release);
}

TEST(SpscRing, TwoThreadStressKeepsOrderAndGapsEqualDrops) {
  SpscRing<TickRecord> ring(8);
  std::atomic<bool> done{false};
  std::thread producer(produce, std::ref(ring), std::ref(done));

  std::vector<TickRecord> out(5);
  std::uint64_t received = 0;
  std::uint64_t gaps = 0;
  std::uint64_t expected = 0;
  bool intact = true;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    const std::size_t n = ring.pop_many(out.data(), out.size());
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint64_t t = out[i].tick;
      if (t < expected || !same_bytes(out[i], make_record(t))) intact = false;
      gaps += t - expected;
      expected = t + 1;
    }
    received += n;
    if (n == 0 && finished) break;  // done was seen before an empty pop: nothing can follow
  }
  producer.join();
  ASSERT_TRUE(intact) << "records out of order or torn";
  const std::uint64_t trailing = kStressRecords - expected;  // dropped after the last popped
  EXPECT_EQ(gaps + trailing, ring.dropped());
  EXPECT_EQ(received + ring.dropped(), kStressRecords);
  EXPECT_GT(ring.dropped(), 0u) << "an 8-slot ring should overflow; the test proves nothing";
}

TEST(SpscRing, TwoThreadStressRunsCarryTheirExactDropCounts) {
  SpscRing<TickRecord> ring(8);
  std::atomic<bool> done{false};
  std::thread producer(produce, std::ref(ring), std::ref(done));

  std::vector<TickRecord> out(5);
  std::uint64_t expected = 0;
  std::uint64_t reported = 0;
  std::uint64_t mismatches = 0;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    std::uint64_t dropped_before = 0;
    const std::size_t n = ring.pop_run(out.data(), out.size(), dropped_before);
    reported += dropped_before;
    if (n > 0 && out[0].tick != expected + dropped_before) ++mismatches;
    for (std::size_t i = 1; i < n; ++i) {
      if (out[i].tick != out[i - 1].tick + 1) ++mismatches;  // no gap inside a run
    }
    if (n > 0) expected = out[n - 1].tick + 1;
    if (n == 0 && finished) break;
  }
  producer.join();
  const std::uint64_t trailing = ring.take_trailing_drops();
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(expected + trailing, kStressRecords);
  EXPECT_EQ(reported + trailing, ring.dropped());
}

}  // namespace
}  // namespace hapticd::telemetry
