// The Novint Falcon's delta mechanism and a plant for its effector, for the reference Falcon
// (falcon_firmware.h). Written here from the geometry libnifalcon publishes (libnifalcon at
// f7c727aa24403ea10dc1507d7d396eeb7d55564a: include/falcon/core/FalconGeometry.h for the
// lengths a..f, r, s and the legs' angles phy; include/falcon/core/FalconKinematic.h getTheta
// for the encoder scale; src/kinematic/FalconKinematicStamper.cpp for the leg frame and the
// command scale, enc = -10000 x torque), in a formulation of its own:
//
// Each leg i sees the effector at P = R(phy_i) x + (-r, -s, 0) (its u, v, w). The shin is a
// parallelogram of length b whose angle theta3 is fixed by P_v alone (cos theta3 = (P_v+f)/b),
// so in the leg's u-w plane the knee (a (cos t, sin t), t the arm angle) and the point
// q = (P_u + c, P_w) are k = d + e + b sin theta3 apart. One constraint per leg,
//   g_i(t_i, x) = |q - a (cos t_i, sin t_i)|^2 - k^2 = 0,
// gives the inverse kinematics (a circle intersection; the branch the Falcon is built in, the
// one Stamper's solution takes), the Jacobian by the implicit function theorem
// (dt_i/dx = -grad_x g_i / dg_i/dt_i) and the forward kinematics by Newton on it.
// Angles are in radians, positions in metres in that frame (z away from the body).
#pragma once

#include <array>
#include <cstdint>
#include <optional>

namespace hapticd::reference::falcon {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<Vec3, 3>;  // row-major

// getTheta: degrees of arm per encoder count, and the angle at count 0.
inline constexpr double kDegreesPerCount = 0.01425 * 360.0 / (1280.0 * 0.110);
inline constexpr double kThetaAtZeroDegrees = 35.0;
// FalconKinematicStamper::getForces: motor command = -10000 x arm torque (N m).
inline constexpr double kCountsPerNewtonMetre = 10000.0;

double theta_of_counts(double counts);  // radians
double counts_of_theta(double theta);   // counts (not rounded)

// The three arm angles for an effector position; nothing outside the reachable space.
std::optional<Vec3> inverse_kinematics(const Vec3& x);
// The position for three arm angles, by Newton from `guess`; nothing if it does not converge.
std::optional<Vec3> forward_kinematics(const Vec3& theta, const Vec3& guess);
// dtheta/dx at x (rows: arms): the torques' map, F = A^T tau.
std::optional<Mat3> arm_rates(const Vec3& x);
// The Jacobian dx/dtheta at x (A's inverse).
std::optional<Mat3> jacobian(const Vec3& x);
std::optional<Mat3> invert(const Mat3& m);

struct MechanismOptions {
  double mass = 0.15;      // kg at the effector (arms, grip and hand together)
  double damping = 3.0;    // N s/m, viscous at the effector
  Vec3 start{0, 0, 0.11};  // where the effector rests at power-on
};

// The effector as a point mass moved by the motors' force F = A^T tau (tau_i = -counts_i /
// 10000 N m) and a hand force the test sets, against viscous damping. The workspace's stops
// are the box below and the reach of the legs: the effector stops there (its speed zeroed).
// No gravity: the arms' weight is not in libnifalcon's sources, and a test sets the hand.
class FalconMechanism {
 public:
  explicit FalconMechanism(const MechanismOptions& o = {});
  void set_motor_commands(const std::array<std::int16_t, 3>& counts) { commands_ = counts; }
  void set_hand_force(const Vec3& f) { hand_ = f; }
  // Advances the plant by dt seconds (in sub-steps of at most 0.25 ms).
  void step(double dt);

  const Vec3& position() const { return x_; }
  const Vec3& velocity() const { return v_; }
  const Vec3& arm_angles() const { return theta_; }
  // The force the motors apply at the effector now, for the commands last given.
  Vec3 motor_force() const;
  const std::array<std::int16_t, 3>& commands() const { return commands_; }

 private:
  void substep(double dt);
  MechanismOptions o_;
  Vec3 x_, v_{}, theta_{}, hand_{};
  std::array<std::int16_t, 3> commands_{};
};

// The workspace box the model stops in (metres, the leg frame's origin).
bool inside_workspace(const Vec3& x);

}  // namespace hapticd::reference::falcon
