// The one seam between the coupling design and a semidefinite-programming library: solve an
// SdpProblem (lmi.h), say whether it was solved, found infeasible or failed, and never print,
// read files or end the process. The design (coupling_synthesis.h) sees only this interface;
// make_sdp_solver() gives the library the build links (docs/math.md says which and why).
// Not RT-safe.
#pragma once

#include <Eigen/Dense>
#include <memory>
#include <string>

#include "analysis/lmi.h"

namespace hapticd::analysis {

struct SdpSolution {
  enum class Status {
    kSolved,      // y is feasible (to the solver's tolerance) and optimal
    kInfeasible,  // the solver certified that no y satisfies the blocks
    kFailed,      // numerical trouble, iteration limit: y, if any, is not to be trusted
  };
  Status status = Status::kFailed;
  Eigen::VectorXd y;
  double objective = 0.0;
  int iterations = 0;
  std::string note;  // the solver's reason, when not solved
};

class SdpSolver {
 public:
  virtual ~SdpSolver() = default;
  // Thread-compatible: one call at a time per solver object.
  virtual SdpSolution solve(const SdpProblem& problem) const = 0;
  virtual std::string name() const = 0;
};

// The solver the design uses.
std::unique_ptr<SdpSolver> make_sdp_solver();

}  // namespace hapticd::analysis
