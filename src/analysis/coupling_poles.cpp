#include "analysis/coupling_poles.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace hapticd::analysis {
namespace {

// The bracket each pole set's bisection starts from, below the incumbent's gamma.
constexpr double kBracket = 0.7;
// The scan before the compass search, for up to two poles: real poles, and pairs at these
// radii and angles (rad per sample), ranked at this fraction of the incumbent's gamma; the
// best few are shaped.
constexpr std::array<double, 8> kScanReal{-0.8, 0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99};
constexpr std::array<double, 3> kScanRadius{0.7, 0.85, 0.93};
constexpr std::array<double, 6> kScanAngle{0.03, 0.06, 0.12, 0.25, 0.5, 1.0};
constexpr double kScanTarget = 0.8;
constexpr std::size_t kScanShaped = 3;

// den with one more real pole, on the scan's grid.
std::vector<Polynomial> added_pole(const Polynomial& den) {
  std::vector<Polynomial> out;
  for (double p : kScanReal) out.push_back(poly_mul(den, {1.0, -p}));
  return out;
}

// Pole polynomials (in w = z^-1) of n = 1 or 2 poles on the scan's grid.
std::vector<Polynomial> scan_grid(std::size_t n) {
  std::vector<Polynomial> out;
  for (std::size_t i = 0; i < kScanReal.size(); ++i) {
    const Polynomial one{1.0, -kScanReal[i]};
    if (n == 1) out.push_back(one);
    for (std::size_t j = i; n == 2 && j < kScanReal.size(); ++j) {
      out.push_back(poly_mul(one, {1.0, -kScanReal[j]}));
    }
  }
  for (double r : kScanRadius) {
    for (double a : kScanAngle) {
      if (n == 2) out.push_back({1.0, -2.0 * r * std::cos(a), r * r});
    }
  }
  return out;
}

// C's poles but z = 1, normalised to den[0] = 1.
Polynomial other_poles(const TransferFunction& c) {
  Polynomial d = poly_trim(poly_deflate(c.den, 1.0));
  const double d0 = d.front();
  for (double& v : d) v /= d0;
  return d;
}

class PoleSearch {
 public:
  PoleSearch(const CouplingSpec& spec, const SdpSolver& solver, const PoleSearchOptions& options,
             const std::function<void(const PoleSearchStep&)>& progress, PoleSearchResult& out)
      : solver_(solver), options_(options), progress_(progress), out_(out), spec_(spec) {}

  // One order: the incumbent's poles with one more at z = 0 (when there is room) and its
  // numerator reshaped (a step), the poles placed from a grid (a step), then the compass search
  // (a step per sweep). False when the step budget ran out first.
  bool order(int n) {
    if (out_.steps >= options_.max_steps) return false;
    if (from_ == 0) from_ = n;
    spec_.order = n;
    CouplingShaper shaper(spec_, solver_, out_.best.coupling);
    std::vector<double> kappa = reflection_of(other_poles(out_.best.coupling));
    kappa.resize(static_cast<std::size_t>(n - 1), 0.0);
    report(n, PoleSearchStep::Kind::kReshape, 0.0, keep(shaper, kappa));
    if (out_.steps < options_.max_steps && !kappa.empty()) {
      const std::vector<Polynomial> grid =
          kappa.size() <= 2 ? scan_grid(kappa.size()) : added_pole(other_poles(out_.best.coupling));
      report(n, PoleSearchStep::Kind::kScan, 0.0, scan(shaper, kappa, grid));
    }
    bool ok = true;
    // A raised order starts next to a converged lower order: smaller steps first.
    const double first = n > from_ ? options_.raised_first_step : options_.first_step;
    int streak = 0;  // sweeps in a row that gained
    for (double h = first; !kappa.empty() && h >= options_.last_step;) {
      if (out_.steps >= options_.max_steps) {
        ok = false;
        break;
      }
      const bool improved = sweep(shaper, kappa, h);
      report(n, PoleSearchStep::Kind::kSweep, h, improved);
      streak = improved ? streak + 1 : 0;
      if (!improved) h *= 0.5;
      if (streak >= 2) h = std::min(2.0 * h, options_.first_step);  // longer strides pay
    }
    out_.sdp_solves += shaper.sdp_solves();
    return ok;
  }

 private:
  // The compass search finds the basin it starts in, so the basins are visited first: with one
  // or two poles, pole sets on a grid of real poles and of pairs by radius and angle (kappa is
  // too coarse a grid: a pair's angle lives in the last digits of k_1); with more, the lower
  // order's poles with the new one on the grid of real poles. They are ranked by the slack
  // their disks need at an ambitious gamma, the best few shaped, and the best of those kept if
  // better.
  bool scan(CouplingShaper& shaper, std::vector<double>& kappa,
            const std::vector<Polynomial>& grid) {
    const double target = kScanTarget * out_.best.verdict.gamma;
    std::vector<std::pair<double, Polynomial>> ranked;
    for (const Polynomial& den : grid) {
      ranked.emplace_back(shaper.slack(den, target), den);
    }
    std::sort(ranked.begin(), ranked.end());
    bool kept = false;
    for (std::size_t i = 0; i < std::min(kScanShaped, ranked.size()); ++i) {
      if (keep(shaper, reflection_of(ranked[i].second))) {
        kappa = reflection_of(ranked[i].second);
        kept = true;
      }
    }
    return kept;
  }

  // The best numerator for kappa's poles, kept when the exact checks find it better.
  bool keep(CouplingShaper& shaper, const std::vector<double>& kappa) {
    const double g = out_.best.verdict.gamma;
    std::optional<ShapedCoupling> c =
        shaper.best(polynomial_of(kappa), kBracket * g, g, options_.tolerance);
    if (!c || !(c->verdict.gamma < g * (1.0 - 0.1 * options_.tolerance))) return false;
    out_.best = std::move(*c);
    return true;
  }

  // Each kappa_i moved by +-h in turn, kept when the disks need less slack at a gamma just
  // below the incumbent's; the pole set so reached is then shaped and kept if it is better.
  bool sweep(CouplingShaper& shaper, std::vector<double>& kappa, double h) {
    const double target = out_.best.verdict.gamma * (1.0 - options_.tolerance);
    const std::vector<double> start = kappa;
    double slack = shaper.slack(polynomial_of(kappa), target);
    for (std::size_t i = 0; i < kappa.size(); ++i) {
      for (double sign : {1.0, -1.0}) {
        std::vector<double> trial = kappa;
        trial[i] += sign * h;
        const double s = shaper.slack(polynomial_of(trial), target);
        if (s < slack - 1e-9) {
          kappa = trial;
          slack = s;
          break;
        }
      }
    }
    if (kappa == start) return false;
    if (keep(shaper, kappa)) return true;
    kappa = start;
    return false;
  }

  void report(int n, PoleSearchStep::Kind kind, double h, bool improved) {
    ++out_.steps;
    if (progress_) progress_({out_.steps, n, kind, h, improved, out_.best.verdict.gamma});
  }

  const SdpSolver& solver_;
  const PoleSearchOptions& options_;
  const std::function<void(const PoleSearchStep&)>& progress_;
  PoleSearchResult& out_;
  CouplingSpec spec_;
  int from_ = 0;  // the first order searched
};

}  // namespace

std::vector<double> reflection_of(const Polynomial& den) {
  Polynomial a = den;
  std::vector<double> kappa(a.size() - 1);
  for (std::size_t m = a.size() - 1; m > 0; --m) {
    const double k = std::clamp(a[m], -1.0 + 1e-12, 1.0 - 1e-12);
    kappa[m - 1] = std::atanh(k);
    Polynomial prev(m);
    for (std::size_t i = 0; i < m; ++i) prev[i] = (a[i] - k * a[m - i]) / (1.0 - k * k);
    a = prev;
  }
  return kappa;
}

Polynomial polynomial_of(const std::vector<double>& kappa) {
  Polynomial a{1.0};
  for (double x : kappa) {
    const double k = std::tanh(x);
    Polynomial next(a.size() + 1, 0.0);
    for (std::size_t i = 0; i < a.size(); ++i) {
      next[i] += a[i];
      next[a.size() - i] += k * a[i];
    }
    a = next;
  }
  return a;
}

PoleSearchResult search_poles(const CouplingSpec& spec, const ShapedCoupling& seed,
                              const SdpSolver& solver, const PoleSearchOptions& options,
                              const std::function<void(const PoleSearchStep&)>& progress) {
  PoleSearchResult out;
  out.best = seed;
  PoleSearch search(spec, solver, options, progress, out);
  const int from = std::max(1, static_cast<int>(poly_trim(seed.coupling.den).size()) - 1);
  out.converged = true;
  for (int n = from; n <= spec.order && out.converged; ++n) out.converged = search.order(n);
  return out;
}

}  // namespace hapticd::analysis
