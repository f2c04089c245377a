// Several axes: the one-axis passivity bound (passivity.h) applied along each wall's normal
// (docs/math.md, "Several axes"). A device M(q) q'' + C(q, q') q' + B_j q' = tau + tau_operator
// dissipates q'^T B_j q'; its kinetic energy stores and returns the rest whatever M(q) is. Of
// every joint motion with task velocity v = J q', the least dissipating one dissipates
// v^T B_c v with B_c = (J B_j^-1 J^T)^-1, so along a normal n the device's damping is
//   b_n = 1 / (n^T J B_j^-1 J^T n)
// and walls in contact together (an edge, a corner), each needing b_req_i along its normal
// n_i, are covered when B_c - sum_i b_req_i n_i n_i^T is positive semidefinite: sufficient,
// and for one wall at a fixed configuration of a device with as many joints as task axes
// (J square and invertible) also necessary. Pure functions of small fixed-size values;
// nothing allocates.
#pragma once

#include <Eigen/Core>
#include <span>

namespace hapticd::analysis {

using Vec3 = Eigen::Matrix<double, 3, 1>;
using Mat3 = Eigen::Matrix<double, 3, 3>;

// The device at one configuration: J (m x n, task m of the rows, joints n of the columns) and
// each joint's physical damping (N s/m or N m s/rad, > 0).
struct DeviceDamping {
  Mat3 jacobian = Mat3::Identity();
  Vec3 joint_damping = Vec3::Zero();
  int m = 1;  // task dimension, 1..3
  int n = 1;  // joints, m..3
};

// One wall's demand along its unit normal: b_req of the one-axis bound for its own K, B, T,
// delay and coupling (passivity_bound).
struct NormalDemand {
  Vec3 normal = Vec3::UnitX();
  double required_damping = 0.0;
};

// The task-space damping B_c = (J B_j^-1 J^T)^-1 (m x m, in the top-left block); false when J
// B_j^-1 J^T is singular (J loses rank, or a joint without damping makes it so).
bool task_damping(const DeviceDamping& d, Mat3& b_c) noexcept;

// b_n: the device's damping along the normal n (the wall's b; n need not be unit): 0 when a
// joint has no damping, +inf when no joint motion moves along n (the wall can do no work),
// NaN for a non-finite input or a zero normal (no wall).
double normal_damping(const DeviceDamping& d, const Vec3& normal) noexcept;

// The smallest eigenvalue of B_c - sum_i b_req_i n_i n_i^T: >= 0 when the walls in contact
// together are covered by the device's damping. -inf when B_c does not exist, or for a wall
// with a zero or non-finite normal or demand.
double contact_margin(const DeviceDamping& d, std::span<const NormalDemand> walls) noexcept;

}  // namespace hapticd::analysis
