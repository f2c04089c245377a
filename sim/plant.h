// The simulated one-axis device: mass m, physical damping b, motor force u held by a ZOH for a
// whole sample period, and an operator (docs/devices.md):
//   m dv/dt = -b v + u + f_op
// hand: f_op = k_h (x_s(t) - x) - b_h v; force: f_op = profile; none: f_op = 0;
// motion/replay: the position is imposed (linear between samples) and f_op is whatever it takes.
//
// Each step is the exact discretisation of this linear system, not an ODE integrator: the state
// [x, v, s, ds/dt, 1, u] carries the profile's generator (s'' = -w^2 (s - offset) for a sine,
// s'' = 0 on a linear segment) and the held force, and Phi = expm(A T) is precomputed. A
// breakpoint strictly inside a period splits that step exactly there. The work done by the
// operator comes from the energy balance with an exact (Van Loan) integral of v^2.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "config/config.h"
#include "sim/profile.h"

namespace hapticd::sim {

class Plant {
 public:
  // x0, v0: initial state (ignored for imposed motion, which starts on its trajectory).
  // replay_positions: one imposed position per sample, required for (and only for) kReplay.
  // Throws std::invalid_argument on non-finite or out-of-range input. All discretisations are
  // computed here; step() only multiplies precomputed matrices.
  Plant(double mass, double damping, const config::OperatorSpec& op, double sample_period_s,
        double x0, double v0, std::vector<double> replay_positions = {});

  // RT-safe: called every tick. Advances exactly one sample period with motor_force held.
  void step(double motor_force) noexcept;
  // Back to the initial state at t = 0 with all energy counters zero. No allocation.
  void reset() noexcept;

  // RT-safe: called every tick. State at the current sample instant.
  double position() const noexcept { return x_; }
  // For imposed motion: the velocity of the last period (of the first period before any step).
  double velocity() const noexcept { return v_; }
  double time_s() const noexcept { return static_cast<double>(k_) * period_; }
  std::uint64_t steps() const noexcept { return k_; }
  double sample_period_s() const noexcept { return period_; }
  double kinetic_energy_j() const noexcept { return 0.5 * mass_ * v_ * v_; }
  // Cumulative since t = 0: work done on the device by the operator (= dKE + dissipated -
  // motor work), energy dissipated in b (integral of b v^2), work done by the motor (of u v).
  double operator_work_j() const noexcept { return operator_work_; }
  double dissipated_j() const noexcept { return dissipated_; }
  double motor_work_j() const noexcept { return motor_work_; }
  // f_op at the current instant (hand, force, none); for imposed motion the force during the
  // last period, excluding the impulses at the sample instants.
  double operator_force() const noexcept;

  config::OperatorSpec::Kind kind() const noexcept { return kind_; }
  // The set-point (hand) or force (force) profile; the zero profile for other kinds.
  const Profile& profile() const noexcept { return profile_; }

 private:
  static constexpr int kN = 6;  // [x, v, s, ds/dt, 1, u]
  using Mat = Eigen::Matrix<double, kN, kN>;
  using Vec = Eigen::Matrix<double, kN, 1>;
  // Transition over one (partial) period and the quadratic form z0' V z0 = integral of v^2.
  struct Discrete {
    Mat phi;
    Mat v2;
  };
  // A breakpoint strictly inside period `period`: lead runs from the previous split point
  // (period start or previous breakpoint) to it, tail from it to the end of the period.
  struct Split {
    std::int64_t period = 0;
    std::size_t knot = 0;
    Discrete lead;
    Discrete tail;
  };

  bool imposed() const noexcept;
  double imposed_position(std::uint64_t k) const noexcept;
  void build_linear(const Mat& a);
  void anchor_generator() noexcept;
  void advance(const Discrete& d, double& v2_integral) noexcept;
  void step_linear(double u) noexcept;
  void step_imposed(double u) noexcept;

  config::OperatorSpec::Kind kind_;
  double mass_;
  double damping_;
  double period_;
  double inv_period_;  // 1 / T, so the step multiplies
  double hand_stiffness_ = 0.0;
  double hand_damping_ = 0.0;
  config::MotionSpec motion_;
  std::vector<double> replay_;
  Profile profile_;

  // Linear kinds.
  Discrete full_;
  std::vector<Split> splits_;
  std::vector<std::int64_t> knot_instant_;  // instant at which each knot counts as passed
  Vec z0_ = Vec::Zero();
  Vec z_ = Vec::Zero();
  std::size_t seg_ = 0;         // profile segment in force at the current instant
  std::size_t next_split_ = 0;  // first split not yet reached

  // Imposed kinds.
  double last_motor_force_ = 0.0;

  std::uint64_t k_ = 0;
  double x_ = 0.0;
  double v_ = 0.0;
  double operator_work_ = 0.0;
  double dissipated_ = 0.0;
  double motor_work_ = 0.0;
};

}  // namespace hapticd::sim
