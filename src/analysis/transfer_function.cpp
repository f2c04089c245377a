#include "analysis/transfer_function.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hapticd::analysis {

TransferFunction tf_constant(double k) { return {{k}, {1.0}}; }

TransferFunction tf_product(const TransferFunction& a, const TransferFunction& b) {
  return {poly_mul(a.num, b.num), poly_mul(a.den, b.den)};
}

TransferFunction tf_sum(const TransferFunction& a, const TransferFunction& b) {
  return {poly_add(poly_mul(a.num, b.den), poly_mul(b.num, a.den)), poly_mul(a.den, b.den)};
}

TransferFunction tf_scale(const TransferFunction& a, double k) {
  return {poly_scale(a.num, k), a.den};
}

TransferFunction tf_delay(const TransferFunction& a, int d) {
  return {poly_shift(a.num, d), a.den};
}

TransferFunction tf_feedback(const TransferFunction& a, const TransferFunction& b) {
  // (Na/Da) / (1 + Na Nb / (Da Db)) = Na Db / (Da Db + Na Nb)
  return {poly_mul(a.num, b.den), poly_add(poly_mul(a.den, b.den), poly_mul(a.num, b.num))};
}

Complex frequency_response(const TransferFunction& a, double theta) {
  const Complex w = std::polar(1.0, -theta);
  return poly_eval(a.num, w) / poly_eval(a.den, w);
}

double dc_gain(const TransferFunction& a) {
  Polynomial n = a.num;
  Polynomial d = a.den;
  // Cancel common factors (1 - w) so a zero at z = 1 that meets a pole there is resolved.
  while (poly_has_root_at(d, 1.0) && poly_has_root_at(n, 1.0) && d.size() > 1 && n.size() > 1) {
    n = poly_deflate(n, 1.0);
    d = poly_deflate(d, 1.0);
  }
  if (poly_has_root_at(d, 1.0)) {
    return poly_has_root_at(n, 1.0) ? 0.0 : std::numeric_limits<double>::infinity();
  }
  if (poly_has_root_at(n, 1.0)) return 0.0;
  return poly_eval(n, 1.0) / poly_eval(d, 1.0);
}

std::vector<Complex> poles(const TransferFunction& a) { return poly_roots_z(a.den); }
std::vector<Complex> zeros(const TransferFunction& a) { return poly_roots_z(a.num); }

double spectral_radius(const TransferFunction& a) {
  double r = 0.0;
  for (const Complex& p : poles(a)) r = std::max(r, std::abs(p));
  return r;
}

bool is_stable(const TransferFunction& a, double margin) {
  return spectral_radius(a) < 1.0 - margin;
}

std::vector<double> simulate(const TransferFunction& a, std::span<const double> u) {
  if (a.den.empty() || a.den[0] == 0.0)
    throw std::invalid_argument("simulate: den[0] must be non-zero");
  const double inv = 1.0 / a.den[0];
  std::vector<double> y(u.size(), 0.0);
  for (std::size_t k = 0; k < u.size(); ++k) {
    double acc = 0.0;
    for (std::size_t i = 0; i < a.num.size() && i <= k; ++i) acc += a.num[i] * u[k - i];
    for (std::size_t i = 1; i < a.den.size() && i <= k; ++i) acc -= a.den[i] * y[k - i];
    y[k] = acc * inv;
  }
  return y;
}

}  // namespace hapticd::analysis
