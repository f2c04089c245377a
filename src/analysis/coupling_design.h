// `hapticd design-coupling`'s mathematics, in two stages. First Naghshtabrizi and Hespanha's
// procedure (Section III-B) with both of its loops bounded, at order min(N, 3): a screen of the
// family d z/(z-1) + D_c alone (exact checks, no solver), cone complementarity runs
// (coupling_synthesis.h) at a few nu = (d, D_c), then a bisection of gamma at the best. Then the
// pole search (coupling_poles.h): the numerator shaped by a convex problem for each pole set,
// the poles placed and moved, the order raised to N. Every coupling it returns passed the
// exact checks (evaluate_coupling); the service verifies it once more with the gate itself.
// Not RT-safe; no I/O: progress goes to a callback.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "analysis/coupling_poles.h"
#include "analysis/coupling_synthesis.h"
#include "analysis/sdp_solver.h"

namespace hapticd::analysis {

inline constexpr int kMaxDesignOrder = 8;  // C(z) of degree 8: LMIs of ~200 variables
// The order of the cone complementarity stage: the paper's. Higher orders are reached from its
// design by the pole search (coupling_poles.h), which can only improve on it; the LMIs' cost
// grows steeply with the order.
inline constexpr int kConeComplementarityOrder = 3;

struct DesignOptions {
  int max_steps = 24;           // outer steps (one cone complementarity run each)
  int max_ccl_iterations = 12;  // SDPs per step (the paper's c; the command's default)
  double tolerance = 0.02;      // gamma's bracket closes at hi <= lo (1 + tolerance)
  int golden_steps = 3;         // golden-section steps on log d after the decade probes
  PoleSearchOptions poles;      // the second stage: its own budget of sweeps
};

// One outer step: what was tried and what came of it (the progress line).
struct DesignStep {
  int index = 0;
  CouplingFamily nu;
  double target = 0.0;  // the gamma asked for
  CclResult::Outcome outcome = CclResult::Outcome::kNotConverged;
  int iterations = 0;
  double found = 0.0;  // exact gamma of the controller found (kFound)
  double best = 0.0;   // best gamma so far (+inf before any)
  double lower = 0.0;  // the bracket's lower end
  enum class Phase { kConeComplementarity, kPoles };
  Phase phase = Phase::kConeComplementarity;
  PoleSearchStep poles;  // kPoles: the sweep
};

struct CouplingDesign {
  enum class Status {
    kDesigned,      // converged: gamma's bracket closed, the coupling passed the exact checks
    kNotConverged,  // the step budget ran out first (the best coupling is not offered)
    kNoCoupling,    // no coupling of this order was found at all
  };
  Status status = Status::kNoCoupling;
  TransferFunction coupling;  // C(z), user units
  CouplingFamily nu;
  CouplingVerdict verdict;   // the exact checks on it
  double gamma_floor = 0.0;  // |W(1) E(1)|^2: no admissible C does better (H(1) = 0)
  double gamma_lower = 0.0;  // where the cone complementarity stage stopped: no bound (docs)
  double gamma_seed = 0.0;   // the cone complementarity stage's design (order <= 3)
  int steps = 0;
  int sdp_solves = 0;
  std::string note;
};

// Throws std::invalid_argument naming what is wrong with spec (as design_coupling does).
void validate_coupling_spec(const CouplingSpec& spec);

// Throws std::invalid_argument naming what is wrong with spec (non-finite numbers, order out
// of 1..kMaxDesignOrder, T, b or the allowed damping not positive, an unstable weight, a wall
// that W (H - E) cannot be bounded for).
CouplingDesign design_coupling(const CouplingSpec& spec, const DesignOptions& options,
                               const SdpSolver& solver,
                               const std::function<void(const DesignStep&)>& progress = {});

}  // namespace hapticd::analysis
