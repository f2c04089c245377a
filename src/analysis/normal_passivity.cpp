#include "analysis/normal_passivity.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

namespace hapticd::analysis {
namespace {

// At most 3 x 3, sized at run time: Eigen keeps it on the stack.
using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;

bool finite(const DeviceDamping& d) {
  return d.jacobian.allFinite() && d.joint_damping.allFinite() && d.m >= 1 && d.m <= 3 &&
         d.n >= d.m && d.n <= 3;
}

// J B_j^-1 J^T (m x m); false when a joint's damping is not positive.
bool mobility(const DeviceDamping& d, Mat3& w) {
  w.setZero();
  if (!(d.joint_damping.head(d.n).minCoeff() > 0)) return false;
  const auto j = d.jacobian.topLeftCorner(d.m, d.n);
  w.topLeftCorner(d.m, d.m) =
      j * d.joint_damping.head(d.n).cwiseInverse().asDiagonal() * j.transpose();
  return true;
}

}  // namespace

bool task_damping(const DeviceDamping& d, Mat3& b_c) noexcept {
  b_c.setZero();
  Mat3 w;
  if (!finite(d) || !mobility(d, w)) return false;
  // W is symmetric positive semidefinite; LDLT with a pivot test tells singular from not.
  const Small block = w.topLeftCorner(d.m, d.m);
  const Eigen::LDLT<Small> ldlt(block);
  const double scale = block.diagonal().cwiseAbs().maxCoeff();
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * scale)) return false;
  b_c.topLeftCorner(d.m, d.m) = ldlt.solve(Small::Identity(d.m, d.m));
  return true;
}

double normal_damping(const DeviceDamping& d, const Vec3& normal) noexcept {
  Mat3 w;
  if (!finite(d) || !normal.allFinite() || !(normal.squaredNorm() > 0)) {
    return std::numeric_limits<double>::quiet_NaN();  // no number, and no wall without a normal
  }
  if (!mobility(d, w)) return 0.0;  // an undamped joint moves along n for free
  const auto n = normal.head(d.m);
  const double mob = n.dot(w.topLeftCorner(d.m, d.m) * n);
  // No joint motion reaches n: the wall can do no work, the device needs no damping there.
  if (!(mob > 0)) return std::numeric_limits<double>::infinity();
  // For the unit normal n / |n|: its components beyond m are directions the device cannot
  // move in, which take nothing from b_n's denominator and still count in its length.
  return normal.squaredNorm() / mob;
}

double contact_margin(const DeviceDamping& d, std::span<const NormalDemand> walls) noexcept {
  Mat3 b_c;
  if (!task_damping(d, b_c)) return -std::numeric_limits<double>::infinity();
  Mat3 left = b_c;
  for (const NormalDemand& w : walls) {
    if (!w.normal.allFinite() || !(w.normal.squaredNorm() > 0) ||
        !std::isfinite(w.required_damping)) {
      return -std::numeric_limits<double>::infinity();
    }
    const Vec3 u = w.normal.normalized();  // only its first m components are task axes
    left -= w.required_damping * u * u.transpose();
  }
  const Small block = left.topLeftCorner(d.m, d.m);
  const Eigen::SelfAdjointEigenSolver<Small> eig(block, Eigen::EigenvaluesOnly);
  return eig.eigenvalues().minCoeff();
}

}  // namespace hapticd::analysis
