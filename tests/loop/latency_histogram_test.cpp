// The compact log-linear histogram: its bucket geometry, and percentiles that agree with the
// exact order statistics to within one bucket, as the old 10 ns-bucket tables did.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "alloc_counter.h"
#include "loop/latency_histogram.h"

namespace hapticd::loop {
namespace {

using H = LatencyHistogram;

TEST(LatencyHistogram, BucketsTileTheLineWithBoundedRelativeWidth) {
  EXPECT_LE(sizeof(H), 4200u) << "small enough to stay in cache between ticks";
  EXPECT_EQ(H::bucket_of(0), 0u);
  EXPECT_EQ(H::bucket_of(15), 15u);
  EXPECT_EQ(H::bucket_of(16), 16u);
  for (std::size_t b = 0; b + 1 < H::kOverflow; ++b) {
    ASSERT_EQ(H::upper_edge(b), H::lower_edge(b + 1)) << b;
    ASSERT_EQ(H::bucket_of(H::lower_edge(b)), b) << b;
    ASSERT_EQ(H::bucket_of(H::upper_edge(b) - 1), b) << b;
    if (H::lower_edge(b) >= 16) {
      // Width at most 1/16 of the value: the resolution every percentile has.
      ASSERT_LE((H::upper_edge(b) - H::lower_edge(b)) * 16, H::lower_edge(b)) << b;
    }
  }
  EXPECT_EQ(H::bucket_of(std::int64_t{1} << 35), H::kOverflow);
  EXPECT_EQ(H::bucket_of(-5), 0u);
}

TEST(LatencyHistogram, PercentilesAreWithinOneBucketOfTheExactValues) {
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> latency(std::log(20'000.0), 0.8);  // ~20 us, long tail
  std::vector<std::int64_t> v;
  H h;
  for (int i = 0; i < 200'000; ++i) {
    v.push_back(static_cast<std::int64_t>(latency(rng)));
    h.record(v.back());
  }
  std::sort(v.begin(), v.end());
  for (double q : {0.5, 0.9, 0.99, 0.999, 0.9999}) {
    const std::int64_t exact = v[static_cast<std::size_t>(std::ceil(q * v.size())) - 1];
    const std::int64_t got = h.percentile_ns(q);
    const std::size_t b = H::bucket_of(exact);
    EXPECT_GE(got, exact) << q;
    EXPECT_LE(got, H::upper_edge(b)) << q << ": more than one bucket above " << exact;
  }
  EXPECT_EQ(h.percentile_ns(1.0), v.back());
  EXPECT_EQ(h.max_ns(), v.back());
}

TEST(LatencyHistogram, OverflowKeepsTheExactMaxAndRecordingNeverAllocates) {
  H h;
  testing::AllocationScope scope;
  h.record(250'004);
  h.record(50'000'000'000);  // 50 s: overflow bucket
  h.record(-5);              // a clock step backwards counts as zero
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(h.count(), 3u);
  EXPECT_EQ(h.percentile_ns(0.6), H::upper_edge(H::bucket_of(250'004)));
  EXPECT_EQ(h.percentile_ns(1.0), 50'000'000'000);
  h.reset();
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.percentile_ns(0.5), 0);
}

}  // namespace
}  // namespace hapticd::loop
