#include "loop/latency_histogram.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace hapticd::loop {

std::size_t LatencyHistogram::bucket_of(std::int64_t ns) noexcept {
  const auto v = static_cast<std::uint64_t>(std::max<std::int64_t>(ns, 0));
  if (v < kSub) return static_cast<std::size_t>(v);
  const int e = std::bit_width(v) - 1;  // v in [2^e, 2^(e+1))
  if (e > kMaxExponent) return kOverflow;
  // The kSubBits bits below the leading one choose the sub-bucket.
  const std::uint64_t mantissa = (v >> (e - kSubBits)) - kSub;
  return static_cast<std::size_t>(e - kSubBits + 1) * kSub + static_cast<std::size_t>(mantissa);
}

std::int64_t LatencyHistogram::lower_edge(std::size_t bucket) noexcept {
  if (bucket < kSub) return static_cast<std::int64_t>(bucket);
  if (bucket >= kOverflow) return std::int64_t{1} << (kMaxExponent + 1);
  const int e = static_cast<int>(bucket / kSub) + kSubBits - 1;
  return static_cast<std::int64_t>(kSub + bucket % kSub) << (e - kSubBits);
}

std::int64_t LatencyHistogram::upper_edge(std::size_t bucket) noexcept {
  if (bucket >= kOverflow) return INT64_MAX;
  return lower_edge(bucket + 1);
}

void LatencyHistogram::record(std::int64_t ns) noexcept {
  ns = std::max<std::int64_t>(ns, 0);
  // One recording thread: a load and a store, no locked read-modify-write.
  constexpr auto r = std::memory_order_relaxed;
  std::atomic<std::uint64_t>& bucket = buckets_[bucket_of(ns)];
  bucket.store(bucket.load(r) + 1, r);
  count_.store(count_.load(r) + 1, r);
  if (ns > max_.load(r)) max_.store(ns, r);
}

std::int64_t LatencyHistogram::percentile_ns(double q) const noexcept {
  constexpr auto r = std::memory_order_relaxed;
  const std::uint64_t count = count_.load(r);
  const std::int64_t max = max_.load(r);
  if (count == 0) return 0;
  if (q >= 1.0) return max;
  const auto rank = std::max<std::uint64_t>(
      static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count))), 1);
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) {
    seen += buckets_[b].load(r);
    if (seen >= rank) return std::min(upper_edge(b), max);
  }
  return max;
}

void LatencyHistogram::reset() noexcept {
  for (auto& b : buckets_) b.store(0, std::memory_order_relaxed);
  count_.store(0, std::memory_order_relaxed);
  max_.store(0, std::memory_order_relaxed);
}

}  // namespace hapticd::loop
