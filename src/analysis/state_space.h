// Discrete-time state-space systems x+ = A x + B u, y = C x + D u (any number of inputs and
// outputs), the realisations and interconnections the coupling design builds its generalised
// plant from. Not RT-safe.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "analysis/polynomial.h"

namespace hapticd::analysis {

struct StateSpace {
  Eigen::MatrixXd a, b, c, d;

  Eigen::Index states() const { return a.rows(); }
  Eigen::Index inputs() const { return d.cols(); }
  Eigen::Index outputs() const { return d.rows(); }
};

// One input, one output per numerator, all over the common denominator `den` (polynomials in
// z^-1, den[0] != 0): the controllable canonical form, max(deg) states.
StateSpace realise(const std::vector<Polynomial>& numerators, const Polynomial& den);

// The static gain y = k u.
StateSpace static_gain(const Eigen::MatrixXd& k);

// y = second(first(u)).
StateSpace series(const StateSpace& first, const StateSpace& second);

// Inputs and outputs side by side: [y1; y2] = diag(s1, s2) [u1; u2].
StateSpace append(const StateSpace& s1, const StateSpace& s2);

// New inputs v with old u = m v; new outputs z = m y.
StateSpace mix_inputs(const StateSpace& s, const Eigen::MatrixXd& m);
StateSpace mix_outputs(const Eigen::MatrixXd& m, const StateSpace& s);

// The same system in balanced coordinates (equal, diagonal controllability and observability
// Gramians): the realisation an LMI solver handles best, where companion forms of clustered
// poles near z = 1 are badly conditioned. Unchanged when A is not stable or the realisation
// not minimal.
StateSpace balanced(const StateSpace& s);

// Largest |eigenvalue| of A (0 without states).
double spectral_radius(const StateSpace& s);

}  // namespace hapticd::analysis
