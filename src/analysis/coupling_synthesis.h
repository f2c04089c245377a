// One step of Naghshtabrizi and Hespanha's numerical procedure (Section III-B): for a fixed
// gamma and nu = (d, D_c), the cone complementarity linearisation of El Ghaoui, Oustry and
// AitRami - a feasible point of the LMIs (21), (22) and (24), then min tr(X_j Y + X Y_j) over
// them, j = 1, 2, ... - until the controller of an iterate passes the exact checks
// (evaluate_coupling: the gate's own DSPR check, passivity bound and transparency gamma), not
// the solver's word. Not RT-safe.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <string>

#include "analysis/coupling_lmis.h"
#include "analysis/sdp_solver.h"

namespace hapticd::analysis {

// The exact verdict on a coupling C(z) for spec, by the functions the gate uses.
struct CouplingVerdict {
  bool theorem1 = false;  // C admissible and (z-1)/(Tz)(C - T/(2b)) DSPR
  double dspr_min_real = 0.0;
  double dspr_worst_theta = -1.0;  // where it is attained (rad per sample), -1 if not reached
  double required_damping = 0.0;   // b_req of E/(1 + E C) with the delay
  double passivity_worst_theta = 0.0;
  bool passive = false;  // b_req <= spec.allowed_damping
  double gamma = 0.0;    // max |W (H - E)|^2
  double gamma_frequency_theta = 0.0;
  bool valid() const { return theorem1 && passive && std::isfinite(gamma); }
  std::string note;  // the first check that fails
};

CouplingVerdict evaluate_coupling(const CouplingSpec& spec, const TransferFunction& coupling);

struct CclResult {
  enum class Outcome {
    kFound,         // a controller with exact gamma <= the target
    kInfeasible,    // the convex relaxation is infeasible: no controller of this order and nu
                    // reaches the target (a certificate, not a failure to converge)
    kNotConverged,  // the iteration limit came first
    kSolverFailed,  // the SDP solver gave up
  };
  Outcome outcome = Outcome::kNotConverged;
  // The best iterate that passed the exact checks with gamma below request.incumbent, even
  // when above the target (improved), else nothing.
  bool improved = false;
  CouplingParameters chi;
  TransferFunction coupling;  // C(z), user units
  CouplingVerdict verdict;    // its exact verdict
  Eigen::VectorXd point;      // its SDP solution: a later run's linearisation point
  int iterations = 0;         // SDPs solved
  std::string note;
};

struct CclRequest {
  double gamma = 0.0;  // the target, user units ((N/m)^2 times W^2)
  double incumbent = std::numeric_limits<double>::infinity();  // the gamma to beat
  int max_iterations = 40;                                     // c of step 5
  const Eigen::VectorXd* start = nullptr;  // a previous point, else step 3's feasible point
};

// A linearisation point at a known controller chi: for each pair X = P and Y = P^-1, with P
// from the pair's original inequality ((17), (18) and the passivity one) at chi, gamma_hat.
// Empty when chi does not satisfy them (or the solver fails).
Eigen::VectorXd point_at(const CouplingLmis& lmis, const CouplingParameters& chi, double gamma_hat,
                         const SdpSolver& solver);

CclResult cone_complementarity(const CouplingSpec& spec, const CouplingScales& scales,
                               const CouplingFamily& nu, const CouplingLmis& lmis,
                               const CclRequest& request, const SdpSolver& solver);

}  // namespace hapticd::analysis
