#include "analysis/state_space.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <stdexcept>

namespace hapticd::analysis {

using Eigen::MatrixXd;

StateSpace realise(const std::vector<Polynomial>& numerators, const Polynomial& den) {
  if (den.empty() || den[0] == 0.0) throw std::invalid_argument("realise: den[0] must be nonzero");
  std::size_t n = den.size() - 1;
  for (const Polynomial& p : numerators) n = std::max(n, p.empty() ? 0 : p.size() - 1);
  const auto coeff = [](const Polynomial& p, std::size_t i) {
    return i < p.size() ? p[i] : 0.0;
  };
  const double a0 = den[0];
  const Eigen::Index ns = static_cast<Eigen::Index>(n);
  const Eigen::Index ny = static_cast<Eigen::Index>(numerators.size());
  StateSpace s{MatrixXd::Zero(ns, ns), MatrixXd::Zero(ns, 1), MatrixXd::Zero(ny, ns),
               MatrixXd::Zero(ny, 1)};
  // x1+ = -sum a_i x_i + u, x_{i+1}+ = x_i: x_i = z^-i u / A(z^-1).
  for (std::size_t i = 1; i <= n; ++i) {
    s.a(0, static_cast<Eigen::Index>(i) - 1) = -coeff(den, i) / a0;
    if (i < n) s.a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i) - 1) = 1.0;
  }
  if (n > 0) s.b(0, 0) = 1.0;
  for (Eigen::Index k = 0; k < ny; ++k) {
    const Polynomial& num = numerators[static_cast<std::size_t>(k)];
    const double b0 = coeff(num, 0) / a0;
    s.d(k, 0) = b0;
    for (std::size_t i = 1; i <= n; ++i) {
      s.c(k, static_cast<Eigen::Index>(i) - 1) = coeff(num, i) / a0 - b0 * coeff(den, i) / a0;
    }
  }
  return s;
}

StateSpace static_gain(const MatrixXd& k) {
  return {MatrixXd::Zero(0, 0), MatrixXd::Zero(0, k.cols()), MatrixXd::Zero(k.rows(), 0), k};
}

StateSpace series(const StateSpace& first, const StateSpace& second) {
  if (first.outputs() != second.inputs()) throw std::invalid_argument("series: size mismatch");
  const Eigen::Index n1 = first.states(), n2 = second.states();
  StateSpace s;
  s.a = MatrixXd::Zero(n1 + n2, n1 + n2);
  s.a.topLeftCorner(n1, n1) = first.a;
  s.a.bottomLeftCorner(n2, n1) = second.b * first.c;
  s.a.bottomRightCorner(n2, n2) = second.a;
  s.b = MatrixXd::Zero(n1 + n2, first.inputs());
  s.b.topRows(n1) = first.b;
  s.b.bottomRows(n2) = second.b * first.d;
  s.c = MatrixXd::Zero(second.outputs(), n1 + n2);
  s.c.leftCols(n1) = second.d * first.c;
  s.c.rightCols(n2) = second.c;
  s.d = second.d * first.d;
  return s;
}

StateSpace append(const StateSpace& s1, const StateSpace& s2) {
  const auto diag = [](const MatrixXd& x, const MatrixXd& y) {
    MatrixXd r = MatrixXd::Zero(x.rows() + y.rows(), x.cols() + y.cols());
    r.topLeftCorner(x.rows(), x.cols()) = x;
    r.bottomRightCorner(y.rows(), y.cols()) = y;
    return r;
  };
  return {diag(s1.a, s2.a), diag(s1.b, s2.b), diag(s1.c, s2.c), diag(s1.d, s2.d)};
}

StateSpace mix_inputs(const StateSpace& s, const MatrixXd& m) {
  if (m.rows() != s.inputs()) throw std::invalid_argument("mix_inputs: size mismatch");
  return {s.a, s.b * m, s.c, s.d * m};
}

StateSpace mix_outputs(const MatrixXd& m, const StateSpace& s) {
  if (m.cols() != s.outputs()) throw std::invalid_argument("mix_outputs: size mismatch");
  return {s.a, s.b, m * s.c, m * s.d};
}

double spectral_radius(const StateSpace& s) {
  if (s.states() == 0) return 0.0;
  return Eigen::EigenSolver<MatrixXd>(s.a, false).eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace hapticd::analysis
