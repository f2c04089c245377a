#include <gtest/gtest.h>

#include "loop/latency_histogram.h"

namespace hapticd::loop {
namespace {

TEST(LatencyHistogram, PercentilesAreBucketUpperEdgesAndMaxIsExact) {
  LatencyHistogram h;
  for (int i = 1; i <= 1000; ++i) h.record(i * 100);  // 100 ns .. 100 us
  EXPECT_EQ(h.count(), 1000u);
  EXPECT_EQ(h.percentile_ns(0.5), 50'010);  // 500th value 50000 ns, bucket [50000, 50010)
  EXPECT_EQ(h.percentile_ns(0.99), 99'010);
  EXPECT_EQ(h.percentile_ns(1.0), 100'000);
  EXPECT_EQ(h.max_ns(), 100'000);
}

TEST(LatencyHistogram, CoarseRangeAndOverflowKeepTheMax) {
  LatencyHistogram h;
  h.record(250'004);        // 10 us buckets above 100 us
  h.record(5'000'000'000);  // 5 s: overflow bucket
  EXPECT_EQ(h.percentile_ns(0.5), 260'000);
  EXPECT_EQ(h.percentile_ns(1.0), 5'000'000'000);
  h.record(-5);  // a clock step backwards counts as zero
  EXPECT_EQ(h.count(), 3u);
}

}  // namespace
}  // namespace hapticd::loop
