// What one simulated drive moves: an axis of its own (SimAxis: a device of one joint, or one
// joint of a bus whose drives each play a device of their own), or one joint of a mechanism it
// shares with the other drives of its bus (Mechanism: a gantry of CAN drives, stepped once a
// period by the first drive to step). The drive's protocol code is the same either way.
#pragma once

#include "config/config.h"
#include "sim/mechanism.h"
#include "sim/sim_axis.h"

namespace hapticd::sim {

class DriveAxis {
 public:
  // Not RT-safe. An axis of its own, from `device`. Throws std::invalid_argument (SimAxis).
  DriveAxis(const config::DeviceConfig& device, double sample_period_s)
      : own_(device, sample_period_s) {}
  // Not RT-safe. Joint `joint` of `shared`, which outlives this. `device` builds the axis
  // plant() reports, the joint's own numbers (its mass, damping and operator as one axis).
  DriveAxis(const config::DeviceConfig& device, double sample_period_s, Mechanism& shared,
            int joint)
      : own_(device, sample_period_s), shared_(&shared), joint_(joint) {}

  // RT-safe: one period with the force held (the mechanism's, when this is its first joint to
  // step in the period).
  void step() noexcept { shared_ ? shared_->step_joint(joint_) : own_.step(); }
  // RT-safe. The force held from the next step on, unclamped.
  void hold_force(double force) noexcept {
    shared_ ? shared_->hold_torque(joint_, force) : own_.hold_force(force);
  }
  // RT-safe. The amplifier; switching it either way drops the held force to zero.
  void set_output(bool on) noexcept {
    shared_ ? shared_->set_output(joint_, on) : own_.set_output(on);
  }
  // RT-safe. The encoder now, in axis units.
  double encoder_position() noexcept {
    return shared_ ? shared_->encoder_position(joint_) : own_.encoder_position();
  }
  // RT-safe. The encoder now, in counts.
  std::int64_t encoder_counts() noexcept {
    return shared_ ? shared_->encoder_counts(joint_) : own_.encoder_counts();
  }
  double velocity() const noexcept {
    return shared_ ? shared_->velocity(joint_) : own_.plant().velocity();
  }
  // The force the motor puts on the axis now.
  double held_force() const noexcept {
    return shared_ ? shared_->held_torque(joint_) : own_.held_force();
  }
  bool output_on() const noexcept {
    return shared_ ? shared_->output_on(joint_) : own_.output_on();
  }
  // The axis of its own (what a device of one joint's operator did); a joint of a mechanism
  // reports through the mechanism's owner.
  const Plant& plant() const noexcept { return own_.plant(); }
  const Mechanism* mechanism() const noexcept { return shared_; }

 private:
  SimAxis own_;
  Mechanism* shared_ = nullptr;
  int joint_ = 0;
};

}  // namespace hapticd::sim
