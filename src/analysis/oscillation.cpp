#include "analysis/oscillation.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "analysis/frequency_search.h"

namespace hapticd::analysis {
namespace {

std::string describe_pole(const char* what, const Complex& z) {
  std::ostringstream os;
  os << what << " (pole at z = " << z.real() << (z.imag() < 0 ? " - " : " + ") << std::abs(z.imag())
     << "j, |z| = " << std::abs(z) << ")";
  return os.str();
}

}  // namespace

OscillationCheck oscillation_check(const TransferFunction& loop) {
  OscillationCheck r;
  // Tustin's E has a simple pole at z = -1: L is unbounded only at the Nyquist point
  // itself, where the criteria are read as the limit theta -> pi.
  bool pole_at_nyquist = false;
  std::vector<double> hints;
  for (const Complex& z : poles(loop)) {
    const double mag = std::abs(z);
    if (mag >= 1.0 - 1e-9) {
      if (std::abs(z + 1.0) < 1e-9) {
        pole_at_nyquist = true;
        continue;
      }
      r.note = describe_pole("L(z) is not stable", z);
      return r;
    }
    if (mag > 0.5) hints.push_back(std::abs(std::arg(z)));
  }
  // (1 + L)^-1 = D / (D + N): the loop without the unilateral constraint must be stable.
  const TransferFunction closed{loop.den, poly_add(loop.den, loop.num)};
  for (const Complex& z : poles(closed)) {
    if (std::abs(z) >= 1.0 - 1e-9) {
      r.note = describe_pole("the linear loop 1/(1 + L) is not stable", z);
      return r;
    }
  }
  if (dc_gain(loop) < 0.0) {
    r.note = "L(1) < 0: the loop's DC gain is negative";
    return r;
  }
  r.applicable = true;

  const double hi = pole_at_nyquist ? std::numbers::pi * (1.0 - 1e-7) : std::numbers::pi;
  const double lo = 1e-6;  // theta -> 0: m -> infinity, the wedge test is trivially met
  const auto wedge = [&](double th) {
    const Complex l = frequency_response(loop, th);
    const double m = std::sin(th) / (1.0 - std::cos(th));
    return l.real() + m * std::abs(l.imag()) + 1.0;
  };
  const auto tsypkin = [&](double th) { return frequency_response(loop, th).real() + 1.0; };
  const Extremum w = minimize_over_frequency(wedge, lo, hi, hints);
  const Extremum t = minimize_over_frequency(tsypkin, lo, hi, hints);
  r.tsai_colgate_margin = w.value;
  r.worst_theta = w.theta;
  r.tsypkin_margin = t.value;
  r.tsai_colgate = w.value > 0.0;
  r.tsypkin = t.value > 0.0;
  return r;
}

}  // namespace hapticd::analysis
