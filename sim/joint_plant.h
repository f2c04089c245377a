// The simulated device of several joints (docs/kinematics.md, the simulated mechanism): each
// joint a mass m and a damping b of its own (device.mass, device.damping), driven by its motor
// torque held over the period, and the hand a spring-damper in task space to a set-point
// moving along a direction (device.sim.operator: origin + setpoint(t) direction):
//   m q_i'' = -b q_i' + tau_i + (J(q)^T f_hand)_i,   f_hand = k_h (x_s(t) - x(q)) - b_h x'
// The joints are decoupled but for the hand, which acts through the kinematics: each period is
// kSubsteps substeps, each the exact step of every joint with the hand's torque of the
// substep's start held. Without a hand (kind none) each period is exact.
#pragma once

#include <cstdint>

#include "config/config.h"
#include "kinematics/kinematics.h"
#include "sim/profile.h"

namespace hapticd::sim {

class JointPlant {
 public:
  // Substeps per period over which the hand's torque is held.
  static constexpr int kSubsteps = 16;

  // Not RT-safe. Throws std::invalid_argument for a kinematics of one joint, an operator kind
  // other than hand or none, or an origin that is not a pose of the mechanism.
  JointPlant(const config::DeviceConfig& device, double sample_period_s);

  // RT-safe: called every tick. Advances one period with `torque` (each joint's) held.
  void step(const kinematics::Vec3& torque) noexcept;
  // Back to rest at the origin, t = 0. No allocation.
  void reset() noexcept;

  int joints() const noexcept { return n_; }
  const kinematics::Vec3& joint_positions() const noexcept { return q_; }
  const kinematics::Vec3& joint_velocities() const noexcept { return qd_; }
  // Where the effector is (forward kinematics of the joints), and the hand's force on it.
  kinematics::Vec3 task_position() const noexcept;
  const kinematics::Vec3& hand_force() const noexcept { return hand_force_; }
  double time_s() const noexcept { return static_cast<double>(k_) * period_; }
  std::uint64_t steps() const noexcept { return k_; }

 private:
  // RT-safe. The hand's force at substep time t (0 without a hand, or off the mechanism).
  kinematics::Vec3 hand_torque(double t) noexcept;

  config::DeviceConfig device_;  // its kinematics, mass, damping and operator
  int n_;
  double period_;
  double h_;  // substep length
  // Each joint's, with its own m and b:
  kinematics::Vec3 decay_ = kinematics::Vec3::Zero();  // exp(-b h / m): velocity over a substep
  kinematics::Vec3 gain_ = kinematics::Vec3::Zero();   // (1 - decay) / b: velocity per unit force
  kinematics::Vec3 drift_ = kinematics::Vec3::Zero();  // (h - gain m) / b: displacement per force
  kinematics::Vec3 coast_ = kinematics::Vec3::Zero();  // gain m: displacement per unit velocity
  Profile setpoint_;
  kinematics::Vec3 q0_ = kinematics::Vec3::Zero();
  kinematics::Vec3 q_ = kinematics::Vec3::Zero();
  kinematics::Vec3 qd_ = kinematics::Vec3::Zero();
  kinematics::Vec3 x_ = kinematics::Vec3::Zero();  // the last forward solution (the delta's guess)
  kinematics::Vec3 hand_force_ = kinematics::Vec3::Zero();
  std::uint64_t k_ = 0;
};

}  // namespace hapticd::sim
