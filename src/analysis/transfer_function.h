// Rational transfer functions in powers of z^-1 and the operations the gate needs: products,
// sums, the contact feedback E/(1+EC), delays, frequency response, poles and stability, and
// time-domain filtering (used to cross-check the controller). Not RT-safe.
#pragma once

#include <complex>
#include <span>
#include <vector>

#include "analysis/polynomial.h"

namespace hapticd::analysis {

// num(z^-1) / den(z^-1); den[0] != 0.
struct TransferFunction {
  Polynomial num{0.0};
  Polynomial den{1.0};
};

TransferFunction tf_constant(double k);
TransferFunction tf_product(const TransferFunction& a, const TransferFunction& b);
TransferFunction tf_sum(const TransferFunction& a, const TransferFunction& b);
TransferFunction tf_scale(const TransferFunction& a, double k);
// z^-d a(z).
TransferFunction tf_delay(const TransferFunction& a, int d);
// The closed loop a / (1 + a b): the wall E seen through the virtual coupling C.
TransferFunction tf_feedback(const TransferFunction& a, const TransferFunction& b);

// a(e^{j theta}), theta = omega T in radians.
Complex frequency_response(const TransferFunction& a, double theta);
// a(z) at z = 1 (DC gain); infinite when z = 1 is a pole that the numerator does not cancel.
double dc_gain(const TransferFunction& a);

std::vector<Complex> poles(const TransferFunction& a);
std::vector<Complex> zeros(const TransferFunction& a);
// All poles strictly inside the unit circle (|z| < 1 - margin).
bool is_stable(const TransferFunction& a, double margin = 1e-9);
// Largest pole magnitude (0 for an FIR filter).
double spectral_radius(const TransferFunction& a);

// y = a applied to u from rest (direct form; den normalised by den[0]).
std::vector<double> simulate(const TransferFunction& a, std::span<const double> u);

}  // namespace hapticd::analysis
