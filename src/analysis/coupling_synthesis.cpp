#include "analysis/coupling_synthesis.h"

#include <array>
#include <cmath>

#include "analysis/coupling.h"
#include "analysis/passivity.h"
#include "analysis/wall_model.h"

namespace hapticd::analysis {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// c'y = sum over pairs of tr(Xw Y) + tr(X Yw): the linearised complementarity objective (step
// 4), or tr(X) + tr(Y) with identity weights (step 3's feasible point).
VectorXd ccl_objective(const CouplingLmis& l, const VectorXd* at) {
  VectorXd c = VectorXd::Zero(l.variables);
  for (const MatrixPair& p : l.pairs) {
    const Eigen::Index n = p.x.rows();
    const MatrixXd xw = at ? evaluate(p.x, *at) : MatrixXd::Identity(n, n);
    const MatrixXd yw = at ? evaluate(p.y, *at) : MatrixXd::Identity(n, n);
    for (const auto& [var, coeff] : p.y.terms) c(var) += xw.cwiseProduct(coeff).sum();
    for (const auto& [var, coeff] : p.x.terms) c(var) += yw.cwiseProduct(coeff).sum();
  }
  return c;
}

VectorXd chi_vector(const CouplingLmis& l, const CouplingParameters& chi) {
  VectorXd y = VectorXd::Zero(l.variables);
  for (std::size_t i = 0; i < l.alpha.size(); ++i) {
    y(l.alpha[i]) = chi.alpha(static_cast<Eigen::Index>(i));
    y(l.c[i]) = chi.c(static_cast<Eigen::Index>(i));
  }
  return y;
}

// Writes the symmetric matrix value into the variables of m (a VariablePool::symmetric).
void assign(const AffineMatrix& m, const MatrixXd& value, VectorXd& y) {
  for (const auto& [var, coeff] : m.terms) {
    Eigen::Index i = 0, j = 0;
    coeff.cwiseAbs().maxCoeff(&i, &j);
    y(var) = value(i, j);
  }
}

// [P - A'PA - C'C, -(A'PB + C'D); ., gamma - B'PB - D'D] (bounded real, pair 0) or
// [P - A'PA, C' - A'PB; ., D + D' - B'PB] (positive real): >= 0 for a P that proves it.
LmiBlock original_inequality(int pair, const AffineMatrix& p, const AffineSystem& sys,
                             const VectorXd& at, double gamma_hat) {
  const MatrixXd a = evaluate(sys.a, at), b = evaluate(sys.b, at);
  const MatrixXd c = evaluate(sys.c, at), d = evaluate(sys.d, at);
  const int n = static_cast<int>(a.rows());
  const AffineMatrix apa = a.transpose() * p * a, bpa = b.transpose() * p * a;
  const AffineMatrix bpb = b.transpose() * p * b;
  if (pair == 0) {
    return lmi_block(
        {n, 1},
        {{{0, 0}, p + (-1.0) * apa + affine(-c.transpose() * c)},
         {{1, 0}, (-1.0) * bpa + affine(-d.transpose() * c)},
         {{1, 1}, affine(MatrixXd::Constant(1, 1, gamma_hat) - d.transpose() * d) + (-1.0) * bpb}});
  }
  return lmi_block({n, 1}, {{{0, 0}, p + (-1.0) * apa},
                            {{1, 0}, affine(c) + (-1.0) * bpa},
                            {{1, 1}, affine(d + d.transpose()) + (-1.0) * bpb}});
}

}  // namespace

VectorXd point_at(const CouplingLmis& lmis, const CouplingParameters& chi, double gamma_hat,
                  const SdpSolver& solver) {
  const VectorXd at = chi_vector(lmis, chi);
  VariablePool pool;
  std::array<AffineMatrix, 3> ps, qs;
  SdpProblem prob;
  for (std::size_t i = 0; i < 3; ++i) {
    const int n = static_cast<int>(lmis.pairs[i].x.rows());
    ps[i] = pool.symmetric(n);
    qs[i] = pool.symmetric(n);
    prob.blocks.push_back(
        original_inequality(static_cast<int>(i), ps[i], lmis.systems[i], at, gamma_hat));
    // [Q I; I P] >= 0 with tr(P + Q) minimal keeps P well inside the cone: Q >= P^-1 bounds
    // it away from singular, as tr(P) bounds it from above.
    prob.blocks.push_back(lmi_block(
        {n, n}, {{{0, 0}, qs[i]}, {{1, 0}, affine(MatrixXd::Identity(n, n))}, {{1, 1}, ps[i]}}));
  }
  prob.variables = pool.count();
  prob.objective = VectorXd::Zero(prob.variables);
  for (std::size_t i = 0; i < 3; ++i) {
    for (const auto& [var, coeff] : ps[i].terms) prob.objective(var) += coeff.trace();
    for (const auto& [var, coeff] : qs[i].terms) prob.objective(var) += coeff.trace();
  }
  prob.margin = 1e-7;
  const SdpSolution s = solver.solve(prob);
  if (s.status != SdpSolution::Status::kSolved) return {};
  VectorXd y = at;
  for (std::size_t i = 0; i < 3; ++i) {
    const MatrixXd p = evaluate(ps[i], s.y);
    assign(lmis.pairs[i].x, p, y);
    assign(lmis.pairs[i].y, p.inverse(), y);
  }
  return y;
}

CouplingVerdict evaluate_coupling(const CouplingSpec& spec, const TransferFunction& coupling) {
  CouplingVerdict v;
  const CouplingCheck cc = coupling_check(coupling, spec.sample_period, spec.device_damping);
  v.theorem1 = cc.admissible && cc.dspr;
  v.dspr_min_real = cc.dspr_min_real;
  if (cc.admissible) v.dspr_worst_theta = cc.dspr_worst_theta;
  const TransferFunction h = contact_map(spec.environment, coupling);
  const PassivityBound pb = passivity_bound(h, spec.sample_period, spec.delay_samples, 0.0);
  v.required_damping = pb.required_damping;
  v.passivity_worst_theta = pb.worst_theta;
  v.passive = std::isfinite(pb.required_damping) && pb.required_damping <= spec.allowed_damping;
  const Extremum g = transparency_gamma(h, spec.environment, spec.weight);
  v.gamma = g.value;
  v.gamma_frequency_theta = g.theta;
  if (!v.theorem1) {
    v.note = "Theorem 1: " + cc.note;
  } else if (!v.passive) {
    v.note = pb.note.empty() ? "passivity: b_req exceeds the damping allowed" : pb.note;
  } else if (!std::isfinite(v.gamma)) {
    v.note = "W (H - E) is unbounded";
  }
  return v;
}

CclResult cone_complementarity(const CouplingSpec& spec, const CouplingScales& scales,
                               const CouplingFamily& nu, const CouplingLmis& lmis,
                               const CclRequest& request, const SdpSolver& solver) {
  CclResult r;
  const double gamma_hat = scales.gamma_hat(request.gamma);
  int total_size = 0;
  for (const MatrixPair& pr : lmis.pairs) total_size += static_cast<int>(pr.x.rows());
  VectorXd point;
  if (request.start != nullptr) point = *request.start;
  double best = request.incumbent;
  for (int j = 0; j <= request.max_iterations; ++j) {
    const bool first = point.size() == 0;
    SdpProblem p = coupling_sdp(lmis, gamma_hat, ccl_objective(lmis, first ? nullptr : &point));
    p.margin = 1e-7;
    const SdpSolution s = solver.solve(p);
    ++r.iterations;
    if (s.status == SdpSolution::Status::kInfeasible) {
      r.outcome = CclResult::Outcome::kInfeasible;
      return r;
    }
    if (s.status != SdpSolution::Status::kSolved) {
      r.outcome = CclResult::Outcome::kSolverFailed;
      r.note = s.note;
      return r;
    }
    point = s.y;
    const CouplingParameters chi = parameters_at(lmis, point);
    const TransferFunction c = coupling_filter_of(scales, nu, chi);
    const CouplingVerdict v = evaluate_coupling(spec, c);
    // How far X is from Y^-1: tr(XY) - n >= 0, zero when the complementarity is reached.
    double gap = -total_size;
    for (const MatrixPair& pr : lmis.pairs)
      gap += (evaluate(pr.x, point) * evaluate(pr.y, point)).trace();
    if (v.valid() && v.gamma < best) {
      best = v.gamma;
      r.improved = true;
      r.chi = chi;
      r.coupling = c;
      r.verdict = v;
      r.point = point;
      if (v.gamma <= request.gamma) {
        r.outcome = CclResult::Outcome::kFound;
        return r;
      }
    }
    if (gap < 1e-6 * total_size) break;  // X = Y^-1 reached: more iterations change nothing
  }
  r.outcome = CclResult::Outcome::kNotConverged;
  return r;
}

}  // namespace hapticd::analysis
