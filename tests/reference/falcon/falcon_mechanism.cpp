#include "falcon_mechanism.h"

#include <algorithm>
#include <cmath>

namespace hapticd::reference::falcon {
namespace {

// FalconGeometry.h (libnifalcon f7c727aa), metres.
constexpr double kA = 0.060, kB = 0.1025, kC = 0.01443, kD = 0.01125, kE = kD, kF = -0.025;
constexpr double kR = 0.0400, kS = -0.02309;
constexpr double kPi = 3.14159265358979323846;
constexpr double kTilt = kPi / 12;  // each leg 15 degrees off the desk plane
constexpr std::array<double, 3> kPhi{kPi / 2 + kTilt, -kPi / 6 + kTilt, -5 * kPi / 6 + kTilt};

// The effector in leg i's frame (u, v, w) and the leg's rotation.
Vec3 in_leg(const Vec3& x, int i) {
  const double cp = std::cos(kPhi[i]), sp = std::sin(kPhi[i]);
  return {cp * x[0] + sp * x[1] - kR, -sp * x[0] + cp * x[1] - kS, x[2]};
}

// The shin's reach k(P_v) and its derivative; nothing where the parallelogram cannot reach.
std::optional<std::pair<double, double>> reach(double pv) {
  const double cv = (pv + kF) / kB;
  if (std::abs(cv) >= 1.0) return std::nullopt;
  const double sv = std::sqrt(1.0 - cv * cv);
  return std::pair{kD + kE + kB * sv, -cv / sv};  // dk/dP_v = b (-cv/sv) (1/b)
}

}  // namespace

double theta_of_counts(double counts) {
  return (counts * kDegreesPerCount + kThetaAtZeroDegrees) * kPi / 180.0;
}
double counts_of_theta(double theta) {
  return (theta * 180.0 / kPi - kThetaAtZeroDegrees) / kDegreesPerCount;
}

std::optional<Vec3> inverse_kinematics(const Vec3& x) {
  Vec3 theta{};
  for (int i = 0; i < 3; ++i) {
    const Vec3 p = in_leg(x, i);
    const auto k = reach(p[1]);
    if (!k) return std::nullopt;
    const double qu = p[0] + kC, qw = p[2];
    const double rho = std::hypot(qu, qw);
    const double cosine = (rho * rho + kA * kA - k->first * k->first) / (2 * kA * rho);
    if (rho < 1e-9 || std::abs(cosine) > 1.0) return std::nullopt;
    // The knee on the side Stamper's solution (and the Falcon) takes: below the line to q.
    theta[i] = std::atan2(qw, qu) - std::acos(cosine);
  }
  return theta;
}

std::optional<Mat3> arm_rates(const Vec3& x) {
  const auto theta = inverse_kinematics(x);
  if (!theta) return std::nullopt;
  Mat3 a{};
  for (int i = 0; i < 3; ++i) {
    const Vec3 p = in_leg(x, i);
    const auto k = reach(p[1]);
    const double t = (*theta)[i];
    const double du = 2 * (p[0] + kC - kA * std::cos(t));
    const double dw = 2 * (p[2] - kA * std::sin(t));
    const double dv = -2 * k->first * k->second;  // d(-k^2)/dP_v
    const double dt = 2 * kA * ((p[0] + kC) * std::sin(t) - p[2] * std::cos(t));
    if (std::abs(dt) < 1e-12) return std::nullopt;
    // grad_x g = R^T grad_P g; R rows (cos, sin, 0), (-sin, cos, 0), (0, 0, 1).
    const double cp = std::cos(kPhi[i]), sp = std::sin(kPhi[i]);
    const Vec3 gx{cp * du - sp * dv, sp * du + cp * dv, dw};
    for (int j = 0; j < 3; ++j) a[i][j] = -gx[j] / dt;
  }
  return a;
}

std::optional<Mat3> invert(const Mat3& m) {
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  if (std::abs(det) < 1e-18) return std::nullopt;
  Mat3 r{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // The cofactor of m[j][i] (the adjugate is the cofactors transposed).
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      r[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
    }
  }
  return r;
}

std::optional<Mat3> jacobian(const Vec3& x) {
  const auto a = arm_rates(x);
  if (!a) return std::nullopt;
  return invert(*a);
}

std::optional<Vec3> forward_kinematics(const Vec3& theta, const Vec3& guess) {
  Vec3 x = guess;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const auto t = inverse_kinematics(x);
    const auto j = jacobian(x);
    if (!t || !j) return std::nullopt;
    const Vec3 e{theta[0] - (*t)[0], theta[1] - (*t)[1], theta[2] - (*t)[2]};
    if (std::max({std::abs(e[0]), std::abs(e[1]), std::abs(e[2])}) < 1e-13) return x;
    for (int i = 0; i < 3; ++i) x[i] += (*j)[i][0] * e[0] + (*j)[i][1] * e[1] + (*j)[i][2] * e[2];
  }
  return std::nullopt;
}

bool inside_workspace(const Vec3& x) {
  return std::abs(x[0]) <= 0.06 && std::abs(x[1]) <= 0.06 && x[2] >= 0.075 && x[2] <= 0.175 &&
         arm_rates(x).has_value();
}

FalconMechanism::FalconMechanism(const MechanismOptions& o) : o_(o), x_(o.start) {
  theta_ = inverse_kinematics(x_).value_or(Vec3{});
}

Vec3 FalconMechanism::motor_force() const {
  const auto a = arm_rates(x_);
  if (!a) return {};
  Vec3 tau{};
  for (int i = 0; i < 3; ++i) tau[i] = -commands_[i] / kCountsPerNewtonMetre;
  Vec3 f{};
  for (int j = 0; j < 3; ++j)
    f[j] = (*a)[0][j] * tau[0] + (*a)[1][j] * tau[1] + (*a)[2][j] * tau[2];
  return f;
}

void FalconMechanism::step(double dt) {
  constexpr double kMaxStep = 0.00025;
  while (dt > 0) {
    const double h = std::min(dt, kMaxStep);
    substep(h);
    dt -= h;
  }
}

void FalconMechanism::substep(double h) {
  const Vec3 f = motor_force();
  Vec3 next = x_;
  for (int i = 0; i < 3; ++i) {
    v_[i] += (f[i] + hand_[i] - o_.damping * v_[i]) / o_.mass * h;  // semi-implicit Euler
    next[i] += v_[i] * h;
  }
  if (!inside_workspace(next)) {
    v_ = {};  // a stop: the effector stays where it was
    return;
  }
  x_ = next;
  theta_ = inverse_kinematics(x_).value_or(theta_);
}

}  // namespace hapticd::reference::falcon
