#include "kinematics/conditioning.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace hapticd::kinematics {
namespace {

// The singular values of a 2 x 2 matrix in closed form (its rotation-plus-reflection split).
SingularValues singular_values_2(double a, double b, double c, double d) noexcept {
  const double q = std::hypot((a + d) / 2, (c - b) / 2);
  const double r = std::hypot((a - d) / 2, (c + b) / 2);
  return SingularValues{q + r, std::abs(q - r)};
}

}  // namespace

SingularValues singular_values(const Mat3& J, int n) noexcept {
  if (!J.allFinite()) return SingularValues{};
  if (n == 1) return SingularValues{std::abs(J(0, 0)), std::abs(J(0, 0))};
  if (n == 2) return singular_values_2(J(0, 0), J(0, 1), J(1, 0), J(1, 1));
  // 3 x 3: the eigenvalues of J^T J (the squared singular values) in closed form, no iteration;
  // near zero a singular value is good to about 1e-8 sigma_max, far below any threshold here.
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(J.transpose() * J, Eigen::EigenvaluesOnly);
  const Vec3& l = eig.eigenvalues();  // ascending
  return SingularValues{std::sqrt(std::max(l[2], 0.0)), std::sqrt(std::max(l[0], 0.0))};
}

double inverse_condition(const Mat3& J, int n) noexcept {
  const SingularValues s = singular_values(J, n);
  return s.largest > 0 ? s.smallest / s.largest : 0.0;
}

bool implicit_jacobian(const Mat3& dg_dx, const Vec3& dg_dq, int n, Mat3& J) noexcept {
  J.setZero();
  double det = 0.0;
  double scale = 1.0;
  if (n == 2) {
    det = dg_dx.topLeftCorner<2, 2>().determinant();
    scale = dg_dx.row(0).head<2>().norm() * dg_dx.row(1).head<2>().norm();
  } else {
    det = dg_dx.determinant();
    scale = dg_dx.row(0).norm() * dg_dx.row(1).norm() * dg_dx.row(2).norm();
  }
  if (!std::isfinite(det) || !(std::abs(det) > 1e-12 * scale)) return false;
  if (n == 2) {
    J.topLeftCorner<2, 2>() = -dg_dx.topLeftCorner<2, 2>().inverse() * dg_dq.head<2>().asDiagonal();
  } else {
    J = -dg_dx.inverse() * dg_dq.asDiagonal();
  }
  return J.allFinite();
}

Status judge(const Box& box, const Vec3& x, int m, const Mat3& J, bool jacobian_ok,
             const SingularityThresholds& near) noexcept {
  if (!inside(box, x, m)) return Status::kOutsideWorkspace;
  if (!jacobian_ok) return Status::kNearSingularity;
  const SingularValues s = singular_values(J, m);
  // A zero (or non-finite) J moves nothing: singular, even with thresholds of zero.
  if (!(s.largest > 0) || !(s.smallest >= near.min_inverse_condition * s.largest) ||
      !(s.smallest >= near.min_singular_value)) {
    return Status::kNearSingularity;
  }
  return Status::kOk;
}

}  // namespace hapticd::kinematics
