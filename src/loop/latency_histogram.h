// Fixed-bucket histogram of durations in nanoseconds, preallocated so the RT thread can record
// every tick in O(1) without allocating; percentiles are read off-RT. Resolution 10 ns below
// 100 us, 10 us up to 100 ms; larger values land in an overflow bucket (the exact max is kept).
#pragma once

#include <cstdint>
#include <vector>

namespace hapticd::loop {

class LatencyHistogram {
 public:
  LatencyHistogram();  // not RT-safe: allocates the buckets

  // RT-safe: called every tick. Negative values count as 0.
  void record(std::int64_t ns) noexcept;

  std::uint64_t count() const noexcept { return count_; }
  std::int64_t max_ns() const noexcept { return max_; }
  // Upper edge of the bucket holding the q-quantile (0 < q <= 1); the exact max for q = 1.
  std::int64_t percentile_ns(double q) const noexcept;
  void reset() noexcept;

 private:
  std::vector<std::uint64_t> buckets_;
  std::uint64_t count_ = 0;
  std::int64_t max_ = 0;
};

}  // namespace hapticd::loop
