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
  const auto coeff = [](const Polynomial& p, std::size_t i) { return i < p.size() ? p[i] : 0.0; };
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

namespace {

// X = A X A' + Q, by the Kronecker form (the systems here have a dozen states at most).
MatrixXd discrete_lyapunov(const MatrixXd& a, const MatrixXd& q) {
  const Eigen::Index n = a.rows();
  MatrixXd k = MatrixXd::Identity(n * n, n * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) k.block(i * n, j * n, n, n) -= a(i, j) * a;
  const Eigen::VectorXd x = k.partialPivLu().solve(q.reshaped());
  return x.reshaped(n, n);
}

}  // namespace

StateSpace balanced(const StateSpace& s) {
  if (s.states() == 0 || spectral_radius(s) >= 1.0) return s;
  const MatrixXd wc = discrete_lyapunov(s.a, s.b * s.b.transpose());
  const MatrixXd wo = discrete_lyapunov(s.a.transpose(), s.c.transpose() * s.c);
  const Eigen::LLT<MatrixXd> lc(0.5 * (wc + wc.transpose()));
  if (lc.info() != Eigen::Success) return s;
  const MatrixXd l = lc.matrixL();
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(l.transpose() * wo * l);
  if (eig.info() != Eigen::Success || eig.eigenvalues().minCoeff() <= 0.0) return s;
  const Eigen::VectorXd sigma = eig.eigenvalues().cwiseSqrt();  // Hankel singular values
  const MatrixXd t = l * eig.eigenvectors() * sigma.cwiseInverse().cwiseSqrt().asDiagonal();
  const MatrixXd ti =
      sigma.cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose() *
      l.triangularView<Eigen::Lower>().solve(MatrixXd::Identity(l.rows(), l.cols()));
  return {ti * s.a * t, ti * s.b, s.c * t, s.d};
}

double spectral_radius(const StateSpace& s) {
  if (s.states() == 0) return 0.0;
  return Eigen::EigenSolver<MatrixXd>(s.a, false).eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace hapticd::analysis
