#include "analysis/polynomial.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapticd::analysis {

Polynomial poly_mul(const Polynomial& a, const Polynomial& b) {
  if (a.empty() || b.empty()) return {0.0};
  Polynomial r(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return r;
}

Polynomial poly_add(const Polynomial& a, const Polynomial& b) {
  Polynomial r(std::max(a.size(), b.size()), 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) r[i] += a[i];
  for (std::size_t i = 0; i < b.size(); ++i) r[i] += b[i];
  return r;
}

Polynomial poly_scale(const Polynomial& a, double k) {
  Polynomial r(a);
  for (double& c : r) c *= k;
  return r;
}

Polynomial poly_shift(const Polynomial& a, int n) {
  if (n < 0) throw std::invalid_argument("poly_shift: negative delay");
  Polynomial r(static_cast<std::size_t>(n), 0.0);
  r.insert(r.end(), a.begin(), a.end());
  return r;
}

Polynomial poly_trim(Polynomial a) {
  while (a.size() > 1 && a.back() == 0.0) a.pop_back();
  if (a.empty()) a.push_back(0.0);
  return a;
}

Complex poly_eval(const Polynomial& a, Complex w) {
  Complex r = 0.0;
  for (auto it = a.rbegin(); it != a.rend(); ++it) r = r * w + *it;
  return r;
}

double poly_eval(const Polynomial& a, double w) {
  double r = 0.0;
  for (auto it = a.rbegin(); it != a.rend(); ++it) r = r * w + *it;
  return r;
}

double poly_norm1(const Polynomial& a) {
  double s = 0.0;
  for (double c : a) s += std::abs(c);
  return s;
}

bool poly_has_root_at(const Polynomial& a, double p, double rel_tol) {
  const double scale = poly_norm1(a);
  if (scale == 0.0) return true;
  return std::abs(poly_eval(a, p)) <= rel_tol * scale;
}

Polynomial poly_deflate(const Polynomial& a, double p) {
  // a(w) = (1 - p w) q(w) + remainder * w^n; forward recursion q_i = a_i + p q_{i-1}.
  const Polynomial t = poly_trim(a);
  if (t.size() < 2) return {0.0};
  Polynomial q(t.size() - 1);
  double carry = 0.0;
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    q[i] = t[i] + p * carry;
    carry = q[i];
  }
  return q;
}

std::vector<Complex> poly_roots_z(const Polynomial& a) {
  // a(z^-1) = z^-n (a0 z^n + a1 z^(n-1) + ... + an): the z-roots are the roots of the
  // polynomial whose descending coefficients are a0..an. Leading zeros of `a` (factors of w)
  // are delays, not roots; trailing zeros are not coefficients at all.
  Polynomial t = poly_trim(a);
  std::size_t first = 0;
  while (first < t.size() && t[first] == 0.0) ++first;
  if (first == t.size()) return {};
  t.erase(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(first));
  const auto n = static_cast<Eigen::Index>(t.size() - 1);
  if (n == 0) return {};
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index j = 0; j < n; ++j) companion(0, j) = -t[static_cast<std::size_t>(j + 1)] / t[0];
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, /*computeEigenvectors=*/false);
  std::vector<Complex> roots;
  roots.reserve(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) roots.push_back(solver.eigenvalues()(i));
  return roots;
}

}  // namespace hapticd::analysis
