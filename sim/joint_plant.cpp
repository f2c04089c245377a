#include "sim/joint_plant.h"

#include <cmath>
#include <stdexcept>

namespace hapticd::sim {

using kinematics::Vec3;

JointPlant::JointPlant(const config::DeviceConfig& device, double sample_period_s)
    : device_(device),
      n_(kinematics::joint_count(device.kinematics)),
      period_(sample_period_s),
      h_(sample_period_s / kSubsteps),
      setpoint_(device.sim.op.setpoint) {
  using Operator = config::OperatorSpec::Kind;
  if (n_ < 2) throw std::invalid_argument("sim: the joint plant is for several joints");
  if (device.sim.op.kind != Operator::kHand && device.sim.op.kind != Operator::kNone) {
    throw std::invalid_argument("sim: a device of several joints takes a hand or no operator");
  }
  for (int i = 0; i < n_; ++i) {
    const double m = device.mass[static_cast<std::size_t>(i)];
    const double b = device.damping[static_cast<std::size_t>(i)];
    if (!(m > 0.0) || !(b > 0.0) || !(sample_period_s > 0.0)) {
      throw std::invalid_argument("sim: mass, damping and the period must be positive");
    }
    decay_[i] = std::exp(-b * h_ / m);
    gain_[i] = -std::expm1(-b * h_ / m) / b;
    drift_[i] = (h_ - gain_[i] * m) / b;
    coast_[i] = gain_[i] * m;
  }
  const kinematics::JointSolution s = kinematics::inverse(device.kinematics, device.sim.op.origin);
  if (s.status != kinematics::Status::kOk) {
    throw std::invalid_argument(std::string("sim: operator.origin is not a pose: ") +
                                kinematics::status_name(s.status));
  }
  q0_ = s.q;
  reset();
}

void JointPlant::reset() noexcept {
  q_ = q0_;
  qd_.setZero();
  x_ = device_.sim.op.origin;
  hand_force_.setZero();
  k_ = 0;
}

Vec3 JointPlant::task_position() const noexcept {
  return kinematics::forward(device_.kinematics, q_, x_).x;
}

Vec3 JointPlant::hand_torque(double t) noexcept {
  const config::OperatorSpec& op = device_.sim.op;
  if (op.kind != config::OperatorSpec::Kind::kHand) return Vec3::Zero();
  const kinematics::Pose pose = kinematics::forward(device_.kinematics, q_, x_);
  if (!pose.x.allFinite() || !pose.J.allFinite()) return Vec3::Zero();
  x_ = pose.x;
  const Vec3 target = op.origin + op.direction * setpoint_.value(t);
  hand_force_ =
      op.stiffness * (target - pose.x) - op.damping * kinematics::task_velocity(pose, qd_);
  return kinematics::joint_torques(pose, hand_force_);
}

void JointPlant::step(const Vec3& torque) noexcept {
  const double t0 = time_s();
  for (int s = 0; s < kSubsteps; ++s) {
    const Vec3 force = torque + hand_torque(t0 + s * h_);
    for (int i = 0; i < n_; ++i) {
      q_[i] += coast_[i] * qd_[i] + drift_[i] * force[i];
      qd_[i] = decay_[i] * qd_[i] + gain_[i] * force[i];
    }
  }
  ++k_;
}

}  // namespace hapticd::sim
