#include "verify/frequency_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

namespace hapticd::verify {

double FrequencySweep::damping_zero(std::int64_t p, std::int64_t q) {
  const std::int64_t g = std::gcd(p, q);
  p /= g;
  q /= g;
  const auto key = std::make_pair(p, q);
  if (auto it = memo_.find(key); it != memo_.end()) return it->second;
  // Whole periods only; an odd period is doubled so a Nyquist-rate transient averages out.
  std::int64_t window = (q % 2 == 1 && nyquist_pole_) ? 2 * q : q;
  while (window < 256) window *= 2;
  const double theta = 2.0 * std::numbers::pi * static_cast<double>(p) / static_cast<double>(q);
  const double zero = measure(theta, q, window);
  memo_[key] = zero;
  sweep_.push_back({theta / (2.0 * std::numbers::pi * period_s_), zero});
  return zero;
}

std::int64_t warmup_ticks(int total_delay, double slowest_pole) {
  std::int64_t warmup = 16 + 4 * total_delay;
  if (slowest_pole > 0.0 && slowest_pole < 1.0) {
    const double settle = std::log(1e-6) / std::log(slowest_pole);
    warmup = std::max<std::int64_t>(warmup, std::llround(std::min(settle, 1e6)));
  }
  return warmup;
}

double worst_damping(FrequencySweep& sweep, bool tustin) {
  constexpr std::int64_t kJ = 64;
  double best = -std::numeric_limits<double>::infinity();
  std::int64_t best_j = 1;
  for (std::int64_t j = 1; j <= (tustin ? kJ - 1 : kJ); ++j) {
    const double v = sweep.damping_zero(j, 2 * kJ);
    if (v > best) {
      best = v;
      best_j = j;
    }
  }
  for (std::int64_t q : {4096, 1024, 512}) best = std::max(best, sweep.damping_zero(1, q));
  constexpr std::int64_t kQ = 4096;
  constexpr std::int64_t kScale = kQ / (2 * kJ);
  std::int64_t lo = std::max<std::int64_t>(1, (best_j - 1) * kScale);
  std::int64_t hi = std::min<std::int64_t>(tustin ? kQ / 2 - 1 : kQ / 2, (best_j + 1) * kScale);
  while (hi - lo > 2) {  // ternary search on a unimodal bracket
    const std::int64_t m1 = lo + (hi - lo) / 3;
    const std::int64_t m2 = hi - (hi - lo) / 3;
    if (sweep.damping_zero(m1, kQ) < sweep.damping_zero(m2, kQ)) {
      lo = m1 + 1;
    } else {
      hi = m2 - 1;
    }
  }
  for (std::int64_t p = lo; p <= hi; ++p) best = std::max(best, sweep.damping_zero(p, kQ));
  return best;
}

double worst_frequency_hz(std::vector<SweepPoint>& points, double best) {
  std::sort(points.begin(), points.end(), [](const SweepPoint& a, const SweepPoint& b) {
    return a.frequency_hz < b.frequency_hz;
  });
  double at = 0.0;
  for (const SweepPoint& s : points)
    if (s.measured_damping == best) at = s.frequency_hz;
  return at;
}

}  // namespace hapticd::verify
