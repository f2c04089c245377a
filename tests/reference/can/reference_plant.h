// What a reference drive moves: one axis of mass m with viscous damping b, the motor's force
// held between commands, and a hand that pushes with a constant force F from a given time on
// (a ramp of `ramp_s` up to it), so a wall of stiffness K must come to rest at F/K inside it.
// Advanced in real time (the drive's clock) by small semi-implicit Euler steps: a physical
// axis, not a sampled model of one. Axis units: m, N (the transmission is the drive's).
#pragma once

#include <atomic>
#include <cstdint>

namespace hapticd::reference {

struct PlantParameters {
  double mass = 0.1;        // kg
  double damping = 2.0;     // N s/m
  double start = -0.02;     // m
  double hand_force = 0.0;  // N, positive: towards +x
  double hand_start_s = 0.2;
  double hand_ramp_s = 0.3;
  double step_s = 20e-6;
};

class ReferencePlant {
 public:
  explicit ReferencePlant(const PlantParameters& p, std::int64_t t0_ns);
  // The drive's thread: runs the axis up to t_ns with the motor force held so far.
  void advance_to(std::int64_t t_ns);
  // The drive's thread: the motor force from now on (N, axis units).
  void hold_motor_force(double f) { motor_force_ = f; }
  double position() const { return x_; }
  double velocity() const { return v_; }
  // Any thread.
  double position_now() const { return published_x_.load(std::memory_order_relaxed); }
  double motor_force_now() const { return published_f_.load(std::memory_order_relaxed); }
  // Any thread: the hand starts its push (its ramp) at t_ns instead of hand_start_s after t0.
  void press_from(std::int64_t t_ns) { hand_start_ns_.store(t_ns); }
  // Any thread: the hand pushes with `f` (N) from now on (a step, once the press's ramp is
  // done: a hand that eases off or presses harder).
  void set_hand_force(double f) { hand_force_.store(f); }

 private:
  double hand(std::int64_t t_ns) const;

  PlantParameters p_;
  std::int64_t t_ns_;
  double x_;
  double v_ = 0.0;
  double motor_force_ = 0.0;
  std::atomic<double> published_x_;
  std::atomic<double> published_f_{0.0};
  std::atomic<std::int64_t> hand_start_ns_;
  std::atomic<double> hand_force_;
};

}  // namespace hapticd::reference
