#include "loop/latency_histogram.h"

#include <algorithm>
#include <cmath>

namespace hapticd::loop {
namespace {
constexpr std::int64_t kFineStep = 10;        // ns
constexpr std::int64_t kFineEnd = 100'000;    // 100 us
constexpr std::int64_t kCoarseStep = 10'000;  // 10 us
constexpr std::int64_t kCoarseEnd = 100'000'000;
constexpr std::size_t kFine = kFineEnd / kFineStep;
constexpr std::size_t kCoarse = (kCoarseEnd - kFineEnd) / kCoarseStep;
constexpr std::size_t kBuckets = kFine + kCoarse + 1;  // + overflow

std::size_t bucket_of(std::int64_t ns) {
  if (ns < kFineEnd) return static_cast<std::size_t>(ns / kFineStep);
  if (ns < kCoarseEnd) return kFine + static_cast<std::size_t>((ns - kFineEnd) / kCoarseStep);
  return kBuckets - 1;
}

std::int64_t upper_edge(std::size_t b) {
  if (b < kFine) return static_cast<std::int64_t>(b + 1) * kFineStep;
  if (b < kFine + kCoarse) return kFineEnd + static_cast<std::int64_t>(b - kFine + 1) * kCoarseStep;
  return kCoarseEnd;
}
}  // namespace

LatencyHistogram::LatencyHistogram() : buckets_(kBuckets, 0) {}

void LatencyHistogram::record(std::int64_t ns) noexcept {
  ns = std::max<std::int64_t>(ns, 0);
  ++buckets_[bucket_of(ns)];
  ++count_;
  max_ = std::max(max_, ns);
}

std::int64_t LatencyHistogram::percentile_ns(double q) const noexcept {
  if (count_ == 0) return 0;
  if (q >= 1.0) return max_;
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < buckets_.size(); ++b) {
    seen += buckets_[b];
    if (seen >= std::max<std::uint64_t>(rank, 1)) return std::min(upper_edge(b), max_);
  }
  return max_;
}

void LatencyHistogram::reset() noexcept {
  std::fill(buckets_.begin(), buckets_.end(), 0);
  count_ = 0;
  max_ = 0;
}

}  // namespace hapticd::loop
