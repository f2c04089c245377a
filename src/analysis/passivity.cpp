#include "analysis/passivity.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include "analysis/frequency_search.h"

namespace hapticd::analysis {
namespace {

// Phi(w) = T H z^-d / (1 - z) with w = z^-1: T/(1 - z) = -T w / (1 - w), so
// Phi = A / B with A = -T w^(1+d) N and B = (1 - w) D. Poles of Phi at z = +-1 (the
// integrator of the bound itself, Tustin's pole at -1) make Phi infinite on the circle but
// keep its real part finite: a simple pole R / (1 - p w) with |w| = 1, p = +-1 has real
// part exactly R / 2. They are split off analytically so the grid never divides by zero.
struct SplitPhi {
  Polynomial a;
  Polynomial b;
  double constant = 0.0;  // sum of R/2 over the split poles
  std::string failure;    // non-empty: the bound is infinite, and why
};

SplitPhi split_unit_circle_poles(const TransferFunction& h, double t, int d) {
  SplitPhi s{poly_scale(poly_shift(h.num, 1 + d), -t), poly_mul({1.0, -1.0}, h.den), 0.0, {}};
  for (double p : {1.0, -1.0}) {
    while (poly_has_root_at(s.b, p) && s.b.size() > 1) {
      if (poly_has_root_at(s.a, p) && s.a.size() > 1) {  // common factor: cancel it
        s.a = poly_deflate(s.a, p);
        s.b = poly_deflate(s.b, p);
        continue;
      }
      const Polynomial b1 = poly_deflate(s.b, p);
      if (poly_has_root_at(b1, p)) {
        s.failure = p > 0 ? "H(z) has a pole at z = 1: the wall integrates, no damping suffices"
                          : "H(z) has a repeated pole at z = -1";
        return s;
      }
      const double r = poly_eval(s.a, p) / poly_eval(b1, p);
      s.a = poly_deflate(poly_add(s.a, poly_scale(b1, -r)), p);
      s.b = b1;
      s.constant += 0.5 * r;
      break;
    }
  }
  for (const Complex& z : poly_roots_z(s.b)) {
    if (std::abs(z) >= 1.0 - 1e-9) {
      std::ostringstream os;
      os << "H(z) is not stable (pole at z = " << z.real() << (z.imag() < 0 ? " - " : " + ")
         << std::abs(z.imag()) << "j): the passivity bound assumes a stable environment";
      s.failure = os.str();
      return s;
    }
  }
  return s;
}

}  // namespace

PassivityBound passivity_bound(const TransferFunction& h, double sample_period, int delay_samples,
                               double passivity_shortage) {
  const SplitPhi s = split_unit_circle_poles(h, sample_period, delay_samples);
  if (!s.failure.empty()) return {std::numeric_limits<double>::infinity(), 0.0, 0.0, s.failure};

  std::vector<double> hints;
  for (const Complex& z : poly_roots_z(s.b))
    if (std::abs(z) > 0.5) hints.push_back(std::abs(std::arg(z)));

  const auto phi = [&](double theta) {
    const Complex w = std::polar(1.0, -theta);
    return (poly_eval(s.a, w) / poly_eval(s.b, w)).real() + s.constant;
  };
  const Extremum m = maximize_over_frequency(phi, 0.0, std::numbers::pi, hints);
  return {m.value + passivity_shortage,
          m.theta,
          m.theta / (2.0 * std::numbers::pi * sample_period),
          {}};
}

StiffnessLimit max_stiffness(const std::function<TransferFunction(double)>& make_h,
                             double sample_period, int delay_samples, double passivity_shortage,
                             double available_damping) {
  const auto passes = [&](double k) {
    const double b_req =
        passivity_bound(make_h(k), sample_period, delay_samples, passivity_shortage)
            .required_damping;
    return std::isfinite(b_req) && b_req <= available_damping;  // an overflow never passes
  };
  // 2^-30 .. 2^60 N/m covers every physical wall; the pass set is an interval for the walls
  // of docs/math.md (b_req is convex in K without coupling), and the scan finds the last
  // pass-to-fail transition otherwise.
  constexpr int kLowExp = -30;
  constexpr int kHighExp = 60;
  double last_pass = -1.0;
  double first_fail_after = -1.0;
  if (passes(0.0)) last_pass = 0.0;
  for (int e = kLowExp; e <= kHighExp; ++e) {
    const double k = std::ldexp(1.0, e);
    if (passes(k)) {
      last_pass = k;
      first_fail_after = -1.0;
    } else if (last_pass >= 0.0 && first_fail_after < 0.0) {
      first_fail_after = k;
    }
  }
  if (last_pass < 0.0) return {StiffnessLimit::Kind::kNone, 0.0};
  if (first_fail_after < 0.0) return {StiffnessLimit::Kind::kUnbounded, last_pass};
  double lo = last_pass;
  double hi = first_fail_after;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (passes(mid) ? lo : hi) = mid;
  }
  return {StiffnessLimit::Kind::kBounded, lo};
}

}  // namespace hapticd::analysis
