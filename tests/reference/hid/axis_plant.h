// The mechanics behind a reference device: one axis with inertia and damping, turned by the
// device's motor and by a hand (a steady push with the hand's own damping, which a test sets
// while the device runs). Integrated in real time by the device's own loop, as the physical
// axis moves between the device's samples. Thread-safe: the device's loop steps it, the test
// reads it and moves the hand.
#pragma once

#include <atomic>
#include <mutex>

namespace hapticd::reference {

class AxisPlant {
 public:
  AxisPlant(double inertia, double damping, double position)
      : inertia_(inertia), damping_(damping), x_(position) {}

  // The device's loop: `dt` seconds under `motor` (N or N m) and the hand.
  void step(double dt, double motor) {
    const std::lock_guard lock(m_);
    const double push = hand_push_.load(), hand_b = hand_damping_.load();
    v_ += dt / inertia_ * (motor + push - (damping_ + hand_b) * v_);  // semi-implicit Euler
    x_ += dt * v_;
    motor_.store(motor);
  }
  // The test: a hand pushing with `push` and damping `damping` from now on.
  void hand(double push, double damping) {
    hand_push_.store(push);
    hand_damping_.store(damping);
  }
  double position() const {
    const std::lock_guard lock(m_);
    return x_;
  }
  double velocity() const {
    const std::lock_guard lock(m_);
    return v_;
  }
  double motor() const { return motor_.load(); }  // the last motor force/torque applied

 private:
  const double inertia_, damping_;
  mutable std::mutex m_;
  double x_, v_ = 0.0;
  std::atomic<double> hand_push_{0.0}, hand_damping_{0.0}, motor_{0.0};
};

}  // namespace hapticd::reference
