#include "analysis/frequency_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace hapticd::analysis {
namespace {

struct Sample {
  double theta;
  double value;
};

double treat(double v) { return std::isnan(v) ? -std::numeric_limits<double>::infinity() : v; }

// Golden-section search for the maximum of a function unimodal on [a, b].
Extremum golden_max(const std::function<double(double)>& f, double a, double b) {
  constexpr double kInvPhi = 0.6180339887498949;
  double c = b - kInvPhi * (b - a);
  double d = a + kInvPhi * (b - a);
  double fc = treat(f(c));
  double fd = treat(f(d));
  for (int i = 0; i < 90 && (b - a) > 1e-15 * (1.0 + std::abs(a)); ++i) {
    if (fc >= fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kInvPhi * (b - a);
      fc = treat(f(c));
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kInvPhi * (b - a);
      fd = treat(f(d));
    }
  }
  return fc >= fd ? Extremum{fc, c} : Extremum{fd, d};
}

}  // namespace

Extremum maximize_over_frequency(const std::function<double(double)>& f, double lo, double hi,
                                 std::span<const double> hints, int grid) {
  std::vector<Sample> s;
  s.reserve(static_cast<std::size_t>(grid) + 1 + 3 * hints.size());
  for (int i = 0; i <= grid; ++i) {
    const double th = lo + (hi - lo) * static_cast<double>(i) / grid;
    s.push_back({th, 0.0});
  }
  // Narrow resonances can hide between grid points; sample around each hinted angle too.
  const double step = (hi - lo) / grid;
  for (double h : hints) {
    for (double off : {-0.25 * step, 0.0, 0.25 * step}) {
      const double th = h + off;
      if (th >= lo && th <= hi) s.push_back({th, 0.0});
    }
  }
  std::sort(s.begin(), s.end(), [](const Sample& x, const Sample& y) { return x.theta < y.theta; });
  for (Sample& p : s) p.value = treat(f(p.theta));

  Extremum best{s.front().value, s.front().theta};
  for (const Sample& p : s)
    if (p.value > best.value) best = {p.value, p.theta};
  if (!std::isfinite(best.value)) return best;

  // Refine the few largest local maxima: the global one may sit in a different lobe from
  // the best grid point when two lobes are nearly equal.
  std::vector<std::size_t> peaks;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const bool left = i == 0 || s[i].value >= s[i - 1].value;
    const bool right = i + 1 == s.size() || s[i].value >= s[i + 1].value;
    if (left && right) peaks.push_back(i);
  }
  std::sort(peaks.begin(), peaks.end(),
            [&](std::size_t a, std::size_t b) { return s[a].value > s[b].value; });
  if (peaks.size() > 8) peaks.resize(8);
  for (std::size_t i : peaks) {
    const double a = s[i == 0 ? 0 : i - 1].theta;
    const double b = s[i + 1 == s.size() ? i : i + 1].theta;
    const Extremum r = golden_max(f, a, b);
    if (r.value > best.value) best = r;
  }
  return best;
}

Extremum minimize_over_frequency(const std::function<double(double)>& f, double lo, double hi,
                                 std::span<const double> hints, int grid) {
  const Extremum m =
      maximize_over_frequency([&](double th) { return -f(th); }, lo, hi, hints, grid);
  return {-m.value, m.theta};
}

}  // namespace hapticd::analysis
