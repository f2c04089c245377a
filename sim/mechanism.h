// The simulated device of several joints as the motors that drive it see it (docs/kinematics.md,
// the simulated mechanism): a JointPlant, each joint's motor (an amplifier switched on and off,
// a torque held by a ZOH, reversed with device.sim.force_reversed) and each joint's encoder
// (device.sim's resolution and noise). The in-process sim of several joints drives every motor
// at once; the simulated drives of one bus (a CAN gantry: sim/peers/can/can_bus_peer.h) each
// drive one joint, and the first of them to step in a period steps the mechanism for all: each
// drive has taken its command before the bus's trigger (a SYNC) reaches any of them.
#pragma once

#include <array>
#include <cstdint>

#include "config/config.h"
#include "kinematics/kinematics.h"
#include "sim/encoder.h"
#include "sim/joint_plant.h"

namespace hapticd::sim {

class Mechanism {
 public:
  // Not RT-safe. Throws std::invalid_argument as JointPlant and Encoder do.
  Mechanism(const config::DeviceConfig& device, double sample_period_s);

  // Back to rest at the origin, t = 0: every amplifier off, every torque zero, the noise
  // re-seeded. No allocation.
  void reset() noexcept;

  // RT-safe. Joint j's amplifier; switching it either way drops its torque to zero.
  void set_output(int joint, bool on) noexcept;
  // RT-safe. Joint j's torque from the next step on, unclamped (saturation is the controller's).
  void hold_torque(int joint, double torque) noexcept { torque_[joint] = torque; }
  // RT-safe: one period with each joint's torque held (zero where its amplifier is off).
  void step() noexcept;
  // RT-safe: joint j's period, from the drive that moves it: the first joint to step in a period
  // steps the mechanism; the others find that period done.
  void step_joint(int joint) noexcept;

  // RT-safe. Joint j's encoder now: floor quantisation and count noise, or exact (ideal).
  double encoder_position(int joint) noexcept {
    return encoder_.reading(plant_.joint_positions()[joint]);
  }
  // RT-safe. The same in whole counts (the GPIO peer's encoder puts each count on its lines).
  std::int64_t encoder_counts(int joint) noexcept {
    return encoder_.counts(plant_.joint_positions()[joint]);
  }
  double velocity(int joint) const noexcept { return plant_.joint_velocities()[joint]; }
  // The torque joint j's motor puts on the mechanism (reversed with device.sim.force_reversed).
  double held_torque(int joint) const noexcept;
  bool output_on(int joint) const noexcept { return on_[static_cast<std::size_t>(joint)]; }
  int joints() const noexcept { return plant_.joints(); }
  const JointPlant& plant() const noexcept { return plant_; }

 private:
  JointPlant plant_;
  Encoder encoder_;  // every joint's, read in turn
  double motor_sign_;
  kinematics::Vec3 torque_ = kinematics::Vec3::Zero();
  std::array<bool, 3> on_{};
  std::array<std::uint64_t, 3> stepped_{};  // each joint's periods, for step_joint
};

}  // namespace hapticd::sim
