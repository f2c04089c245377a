// The most transparent coupling for given poles, a convex problem (docs/math.md, "Shaping the
// coupling"). Write Naghshtabrizi and Hespanha's C as C = T/(2b) + T P / (1 - z^-1): Theorem 1
// is Re P > 0 on the circle, linear in P. With x = 1 + E C, |W (H - E)|^2 <= gamma is, at each
// frequency, |1/x - 1| <= rho = sqrt(gamma) / |W E|: a disk for x when rho < 1, and Re x >= 1/2
// suffices when rho >= 1. With P = sum m_k z^-k / D(z^-1) and D fixed, x is affine in m, so
// at each gamma the question is an SDP in m (a 2 x 2 block per frequency of a grid, the scalar
// inequalities in one diagonal block). The gate's passivity bound, Re{T z^-d E / ((1 - z) x)}
// <= b_allowed, is not convex in x; it is linearised at a coupling that meets it (an inner
// approximation). The grid gives candidates only: each is kept when the exact checks the
// gate uses (evaluate_coupling) pass it. Not RT-safe.
#pragma once

#include <Eigen/Dense>
#include <optional>
#include <vector>

#include "analysis/coupling_synthesis.h"
#include "analysis/sdp_solver.h"

namespace hapticd::analysis {

struct ShapedCoupling {
  TransferFunction coupling;  // C(z), user units
  CouplingVerdict verdict;    // its exact verdict: valid()
};

class CouplingShaper {
 public:
  // The passivity inequality is linearised at `passive`, a coupling the exact checks pass.
  CouplingShaper(const CouplingSpec& spec, const SdpSolver& solver,
                 const TransferFunction& passive);

  // C's poles but the one at z = 1: den(z^-1), den[0] = 1, of degree at most order - 1.
  // How much every disk must grow for the poles to reach gamma on the grid (<= 0: reached);
  // +inf when the SDP is infeasible or fails. One SDP.
  double slack(const Polynomial& den, double gamma);

  // The most transparent numerator for den: gamma searched in [lo, hi] to a relative
  // tolerance. The best candidate the exact checks pass, nothing when none does.
  std::optional<ShapedCoupling> best(const Polynomial& den, double lo, double hi, double tolerance);

  int sdp_solves() const { return sdp_solves_; }

 private:
  struct Point {
    double theta;
    Complex e, x0, g, a, xhat;
    double we;  // |W E|
  };
  struct Solution {
    double t = 0.0;
    Eigen::VectorXd m;
  };
  void add_point(double theta);
  std::optional<Solution> solve(const Polynomial& den, double gamma);
  TransferFunction coupling_of(const Polynomial& den, const Eigen::VectorXd& m) const;
  std::optional<ShapedCoupling> verified(const Polynomial& den, double gamma);

  const CouplingSpec& spec_;
  const SdpSolver& solver_;
  TransferFunction passive_;
  double unit_ = 0.0;  // T/(2b): P in these units
  std::vector<Point> grid_;
  int sdp_solves_ = 0;
};

}  // namespace hapticd::analysis
