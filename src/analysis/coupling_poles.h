// The poles of the coupling, searched with the numerator shaped for each (coupling_shaping.h),
// and the order raised one at a time from a lower-order design (docs/math.md, "Shaping the
// coupling"). Raising the order by a pole at z = 0 leaves every lower-order coupling in reach
// (its numerator is that of the lower order with a zero coefficient), so each order starts
// where the one below ended and can only do better. The poles other than z = 1 are held as
// the reflection coefficients k_i = tanh(kappa_i) of their polynomial, so every pole set tried
// is stable; a compass search over kappa, its step doubled (up to first_step) after a sweep
// that gains and halved after one that does not, is
// converged when the step falls below last_step. Every coupling it keeps passed the exact
// checks (evaluate_coupling). Not RT-safe.
#pragma once

#include <functional>

#include "analysis/coupling_shaping.h"

namespace hapticd::analysis {

struct PoleSearchOptions {
  int max_steps = 100;               // sweeps, over all orders together
  double first_step = 0.5;           // of kappa
  double raised_first_step = 0.125;  // of kappa, at the orders raised by a pole at z = 0
  double last_step = 0.03;           // converged below this
  double tolerance = 1e-3;           // gamma's bisection for each pole set kept
};

struct PoleSearchStep {
  enum class Kind { kReshape, kScan, kSweep };
  int index = 0;  // steps so far, this one included
  int order = 0;
  Kind kind = Kind::kSweep;
  double step = 0.0;  // kSweep: how far each kappa_i was moved
  bool improved = false;
  double best = 0.0;  // exact gamma of the best coupling so far
};

struct PoleSearchResult {
  bool converged = false;
  ShapedCoupling best;
  int steps = 0;
  int sdp_solves = 0;
};

// Polynomial (den[0] = 1, stable) <-> kappa: the step-down and step-up (Levinson) recursions.
std::vector<double> reflection_of(const Polynomial& den);
Polynomial polynomial_of(const std::vector<double>& kappa);

// From seed, a coupling the exact checks pass with a pole at z = 1 and order at most
// spec.order, to spec.order.
PoleSearchResult search_poles(const CouplingSpec& spec, const ShapedCoupling& seed,
                              const SdpSolver& solver, const PoleSearchOptions& options,
                              const std::function<void(const PoleSearchStep&)>& progress = {});

}  // namespace hapticd::analysis
