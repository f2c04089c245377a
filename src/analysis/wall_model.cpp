#include "analysis/wall_model.h"

// Eigen's matrix-function module triggers warnings the project's flags turn into errors.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wold-style-cast"
#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#pragma GCC diagnostic pop

namespace hapticd::analysis {

TransferFunction environment_filter(const WallParams& wall) {
  const double k = wall.stiffness;
  const double b = wall.damping;
  const double t = wall.sample_period;
  if (wall.discretization == WallDiscretization::kBackward) {
    return {{k + b / t, -b / t}, {1.0}};
  }
  // (K (1 + w) + (2B/T)(1 - w)) / (1 + w)
  return {{k + 2.0 * b / t, k - 2.0 * b / t}, {1.0, 1.0}};
}

TransferFunction contact_map(const TransferFunction& environment,
                             const std::optional<TransferFunction>& coupling) {
  if (!coupling) return environment;
  return tf_feedback(environment, *coupling);
}

TransferFunction device_operator_zoh(double mass, double damping, double operator_stiffness,
                                     double operator_damping, double sample_period) {
  // State x = [position, velocity], input held force u: x' = A x + B u. The augmented
  // exponential exp([[A, B], [0, 0]] T) gives Phi = e^{AT} and Gamma = int_0^T e^{As} ds B.
  const double c = damping + operator_damping;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  m(0, 1) = 1.0;
  m(1, 0) = -operator_stiffness / mass;
  m(1, 1) = -c / mass;
  m(1, 2) = 1.0 / mass;
  const Eigen::Matrix3d e = (m * sample_period).exp();
  const double p11 = e(0, 0), p12 = e(0, 1), p21 = e(1, 0), p22 = e(1, 1);
  const double g1 = e(0, 2), g2 = e(1, 2);
  // G(z) = [1 0] (zI - Phi)^-1 Gamma = (g1 z + p12 g2 - p22 g1) / (z^2 - tr z + det)
  const double trace = p11 + p22;
  const double det = p11 * p22 - p12 * p21;
  return {{0.0, g1, p12 * g2 - p22 * g1}, {1.0, -trace, det}};
}

}  // namespace hapticd::analysis
