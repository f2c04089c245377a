// The parts of a reference serial device's mechanics both boards share: a joint's inertia and
// damping, a task-space vector, and one rotary joint turned by its motor and by a hand (a steady
// push with the hand's own damping, which the test sets while the device runs), as
// tests/reference/hid/axis_plant.h has one linear axis. Stepped by the device's own loop in real
// time, semi-implicit Euler with the damping taken implicitly (stable for any hand at 1 kHz).
// Thread-safe: the device's loop steps it, the test reads it and moves the hand.
#pragma once

#include <mutex>

namespace hapticd::reference {

struct Vec2 {
  double x = 0.0, y = 0.0;
};

struct JointMechanics {
  double inertia = 5e-5;  // kg m^2 about the shaft
  double damping = 1e-3;  // N m s/rad
};

class RotaryJoint {
 public:
  explicit RotaryJoint(JointMechanics m = {}, double angle = 0.0) : m_(m), theta_(angle) {}

  // The device's loop: `dt` seconds under the motor's `torque` (N m) and the hand.
  void step(double dt, double torque) {
    const std::lock_guard lock(mutex_);
    omega_ = (m_.inertia * omega_ + dt * (torque + push_)) /
             (m_.inertia + dt * (m_.damping + hand_damping_));
    theta_ += dt * omega_;
    motor_ = torque;
  }
  // The test: a hand turning the joint with `push_Nm` and damping `damping` (N m s/rad).
  void hand(double push_Nm, double damping) {
    const std::lock_guard lock(mutex_);
    push_ = push_Nm;
    hand_damping_ = damping;
  }
  double angle() const {  // rad
    const std::lock_guard lock(mutex_);
    return theta_;
  }
  double velocity() const {  // rad/s
    const std::lock_guard lock(mutex_);
    return omega_;
  }
  double motor() const {  // the motor torque of the last step, N m
    const std::lock_guard lock(mutex_);
    return motor_;
  }

 private:
  const JointMechanics m_;
  mutable std::mutex mutex_;
  double theta_, omega_ = 0.0, motor_ = 0.0, push_ = 0.0, hand_damping_ = 0.0;
};

}  // namespace hapticd::reference
