// Real polynomials in w = z^-1, stored by ascending power: {a0, a1, ...} = a0 + a1 w + ...
// The building block of every transfer function in the analysis library. Not RT-safe
// (allocates); used at start-up and by `hapticd check`.
#pragma once

#include <complex>
#include <vector>

namespace hapticd::analysis {

using Polynomial = std::vector<double>;
using Complex = std::complex<double>;

Polynomial poly_mul(const Polynomial& a, const Polynomial& b);
Polynomial poly_add(const Polynomial& a, const Polynomial& b);
Polynomial poly_scale(const Polynomial& a, double k);
// Multiplies by w^n (n samples of delay).
Polynomial poly_shift(const Polynomial& a, int n);
// Drops trailing (highest-power) coefficients that are exactly zero; keeps at least one.
Polynomial poly_trim(Polynomial a);
Complex poly_eval(const Polynomial& a, Complex w);
double poly_eval(const Polynomial& a, double w);
// Sum of |coefficients|: the scale against which "is zero" is judged.
double poly_norm1(const Polynomial& a);

// True when p (real) is a root of a within a relative tolerance of the coefficient scale.
bool poly_has_root_at(const Polynomial& a, double p, double rel_tol = 1e-9);
// Divides a by (1 - p w) assuming p is a root; the (tiny) remainder is discarded.
Polynomial poly_deflate(const Polynomial& a, double p);

// Roots in the z-plane of a polynomial in z^-1 (its zeros as a transfer-function factor).
// Factors of w (pure delays) are not roots. Empty for a constant.
std::vector<Complex> poly_roots_z(const Polynomial& a);

}  // namespace hapticd::analysis
