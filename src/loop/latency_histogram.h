// Log-linear histogram of durations in nanoseconds (the HDR-histogram layout): exact below
// 16 ns, then 16 buckets per power of two, so every bucket is at most 1/16 of its value wide.
// 513 buckets (4 KB) reach 2^35 ns (34 s); larger values land in an overflow bucket and the
// exact maximum is kept. The RT thread records into it every tick: small enough to stay in
// cache after a sleep, where the fixed 10 ns-bucket tables it replaces (160 KB each) were cold
// memory the next wake-up paid for. No allocation anywhere. One thread records; any thread
// may read percentiles meanwhile (the counters are relaxed atomics: a reader sees each bucket
// whole, and a percentile a tick or two old).
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace hapticd::loop {

class LatencyHistogram {
 public:
  static constexpr int kSubBits = 4;       // 16 buckets per octave
  static constexpr int kMaxExponent = 34;  // the last octave is [2^34, 2^35) ns
  static constexpr std::size_t kSub = std::size_t{1} << kSubBits;
  static constexpr std::size_t kOverflow = (kMaxExponent - kSubBits + 2) * kSub;
  static constexpr std::size_t kBuckets = kOverflow + 1;

  // RT-safe: called every tick. Negative values (a clock step backwards) count as 0.
  void record(std::int64_t ns) noexcept;

  std::uint64_t count() const noexcept { return count_.load(std::memory_order_relaxed); }
  std::int64_t max_ns() const noexcept { return max_.load(std::memory_order_relaxed); }
  // Upper edge of the bucket holding the q-quantile (0 < q <= 1), never above the exact max;
  // the exact max for q = 1.
  std::int64_t percentile_ns(double q) const noexcept;
  void reset() noexcept;

  // The bucket a value lands in, and that bucket's [lower, upper) edges.
  static std::size_t bucket_of(std::int64_t ns) noexcept;
  static std::int64_t lower_edge(std::size_t bucket) noexcept;
  static std::int64_t upper_edge(std::size_t bucket) noexcept;

 private:
  std::array<std::atomic<std::uint64_t>, kBuckets> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> max_{0};
};

}  // namespace hapticd::loop
