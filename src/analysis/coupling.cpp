#include "analysis/coupling.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

namespace hapticd::analysis {

CouplingCheck coupling_check(const TransferFunction& coupling, double sample_period,
                             double device_damping) {
  CouplingCheck r;
  Polynomial den = coupling.den;
  r.pole_at_one = poly_has_root_at(den, 1.0) && den.size() > 1;
  Polynomial den_rest = r.pole_at_one ? poly_deflate(den, 1.0) : den;
  for (const Complex& z : poly_roots_z(den_rest)) {
    if (std::abs(z) >= 1.0 - 1e-9) {
      std::ostringstream os;
      os << "C(z) has a pole at z = " << z.real() << (z.imag() < 0 ? " - " : " + ")
         << std::abs(z.imag()) << "j on or outside the unit circle"
         << (std::abs(z - 1.0) < 1e-6 ? " (a repeated pole at z = 1)" : "");
      r.note = os.str();
      return r;
    }
  }
  r.admissible = true;

  // M(z) = (1 - w)/T * (Nc - (T/2b) Dc) / Dc. With C's pole at z = 1 the factor (1 - w)
  // cancels it; without one, M(1) = 0 and the strict inequality fails at DC (Naghshtabrizi & Hespanha,
  // Remark 1: a coupling needs that integrator).
  const Polynomial shifted =
      poly_add(coupling.num, poly_scale(den, -sample_period / (2.0 * device_damping)));
  TransferFunction m;
  if (r.pole_at_one) {
    m = {poly_scale(shifted, 1.0 / sample_period), den_rest};
  } else {
    m = {poly_scale(poly_mul({1.0, -1.0}, shifted), 1.0 / sample_period), den};
  }
  std::vector<double> hints;
  for (const Complex& z : poles(m))
    if (std::abs(z) > 0.5) hints.push_back(std::abs(std::arg(z)));
  const Extremum e = minimize_over_frequency(
      [&](double th) { return frequency_response(m, th).real(); }, 0.0, std::numbers::pi, hints);
  r.dspr_min_real = e.value;
  r.dspr_worst_theta = e.theta;
  r.dspr = e.value > 0.0;
  if (!r.dspr) {
    r.note = r.pole_at_one ? "Re{(z-1)/(Tz)(C(z) - T/(2b))} is not positive on the whole circle"
                           : "C(z) has no pole at z = 1, so (z-1)/(Tz)(C - T/(2b)) vanishes at DC";
  }
  return r;
}

Extremum transparency_gamma(const TransferFunction& contact_map,
                            const TransferFunction& environment, const TransferFunction& weight) {
  const TransferFunction err = tf_product(weight, tf_sum(contact_map, tf_scale(environment, -1.0)));
  if (poly_norm1(err.num) == 0.0) return {0.0, 0.0};  // H == E: nothing is distorted
  std::vector<double> hints;
  for (const Complex& z : poles(err)) {
    if (std::abs(z) >= 1.0 - 1e-9) {
      return {std::numeric_limits<double>::infinity(), std::abs(std::arg(z))};
    }
    if (std::abs(z) > 0.5) hints.push_back(std::abs(std::arg(z)));
  }
  return maximize_over_frequency([&](double th) { return std::norm(frequency_response(err, th)); },
                                 0.0, std::numbers::pi, hints);
}

double static_stiffness(const TransferFunction& environment,
                        const std::optional<TransferFunction>& coupling) {
  const double e1 = dc_gain(environment);
  if (!coupling) return e1;
  if (poly_has_root_at(coupling->den, 1.0) && !poly_has_root_at(coupling->num, 1.0)) return 0.0;
  const double c1 = dc_gain(*coupling);
  return e1 / (1.0 + e1 * c1);
}

}  // namespace hapticd::analysis
