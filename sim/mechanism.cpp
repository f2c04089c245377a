#include "sim/mechanism.h"

namespace hapticd::sim {

Mechanism::Mechanism(const config::DeviceConfig& device, double sample_period_s)
    : plant_(device, sample_period_s),
      encoder_(device.sim),
      motor_sign_(device.sim.force_reversed ? -1.0 : 1.0) {
  reset();
}

void Mechanism::reset() noexcept {
  plant_.reset();
  torque_.setZero();
  on_.fill(false);
  stepped_.fill(0);
  encoder_.reset();
}

void Mechanism::set_output(int joint, bool on) noexcept {
  on_[static_cast<std::size_t>(joint)] = on;
  torque_[joint] = 0.0;
}

double Mechanism::held_torque(int joint) const noexcept {
  return on_[static_cast<std::size_t>(joint)] ? motor_sign_ * torque_[joint] : 0.0;
}

void Mechanism::step() noexcept {
  kinematics::Vec3 held = kinematics::Vec3::Zero();
  for (int i = 0; i < joints(); ++i) held[i] = held_torque(i);
  plant_.step(held);
}

void Mechanism::step_joint(int joint) noexcept {
  if (++stepped_[static_cast<std::size_t>(joint)] > plant_.steps()) step();
}

}  // namespace hapticd::sim
