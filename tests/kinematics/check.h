// What the kinematics tests share: a grid over a box, the Jacobian by central differences of the
// forward kinematics, and the relative error between two Jacobians.
#pragma once

#include <functional>
#include <ostream>

#include "kinematics/pose.h"

namespace hapticd::kinematics {

// GoogleTest prints a status by its name. Every test file that compares statuses includes this
// (a file without it would instantiate the byte printer for Status, and the linker keeps one).
inline std::ostream& operator<<(std::ostream& os, Status s) { return os << status_name(s); }

}  // namespace hapticd::kinematics

namespace hapticd::kinematics::testing {

// The points of an n-per-axis grid over the first m coordinates of a box, 1 um inside its faces
// (a point computed on a face can round either way).
template <typename F>
void over_box(const Box& b, int m, int n, F f) {
  const Vec3 lo = b.lower + Vec3::Constant(1e-6), span = b.upper - b.lower - Vec3::Constant(2e-6);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < (m == 3 ? n : 1); ++k) {
        Vec3 x = lo + span.cwiseProduct(Vec3(i, j, k) / (n - 1));
        if (m == 2) x[2] = 0.0;
        f(x);
      }
    }
  }
}

// dx/dq by central differences of `fk` at q, step h, n joints and m task coordinates.
inline Mat3 numeric_jacobian(const std::function<Vec3(const Vec3&)>& fk, const Vec3& q, int n,
                             double h) {
  Mat3 J = Mat3::Zero();
  for (int j = 0; j < n; ++j) {
    Vec3 dq = Vec3::Zero();
    dq[j] = h;
    J.col(j) = (fk(q + dq) - fk(q - dq)) / (2 * h);
  }
  return J;
}

// |A - B| / |B| in the Frobenius norm.
inline double relative_error(const Mat3& a, const Mat3& b) { return (a - b).norm() / b.norm(); }

}  // namespace hapticd::kinematics::testing
