// The mechanism behind the Haply reference board: a five-bar pantograph (Haply 2DIY class) with
// the link lengths and the frame of Haply-API-cpp's Pantograph.cpp (HaplyHaptics/Haply-API-cpp
// at c336a06, src/Haply/Pantograph.cpp): motor 1 at (0, 0), motor 2 at (d, 0), proximal links l
// = 0.05 m, distal links L = 0.07 m, d = 0.02 m, shaft angles theta1, theta2 from +x, and of the
// two places the distal links can meet, the one Pantograph.cpp's forward kinematics picks,
// y_E = (-b + sqrt(Delta)) / (2a): the one of greater y.
//
// Written here from the geometry, not copied: the effector is where the circles of radius L
// about the elbows A and B meet, and the velocity Jacobian comes from differentiating
// |E - A|^2 = L^2 and |E - B|^2 = L^2. Pantograph.cpp's J11..J22 are this Jacobian's transpose
// divided by l (J11 = dx/dtheta1 / l, J12 = dy/dtheta1 / l, J21 = dx/dtheta2 / l, J22 =
// dy/dtheta2 / l; checked against finite differences of the forward kinematics): a force f at the
// effector puts tau = Jv^T f on the shafts, which is l * (J11 fx + J12 fy, J21 fx + J22 fy) in
// Pantograph.cpp's terms. (Its torqueCalculation multiplies by gain 0.1 where the physics has l =
// 0.05, so a host using it commands twice the torque J^T f of the force it asks for.)
//
// The state is the two shaft angles (rad) and velocities; each shaft has its own inertia and
// damping; the hand acts at the effector: f = push - damping * v_E, v_E = Jv * omega. Stepped by
// semi-implicit Euler with the damping (the shafts' and the hand's, mapped by Jv) taken
// implicitly, so a stiff hand cannot make it unstable at 1 kHz. A step that would take the
// mechanism out of reach (elbows more than 2L apart) or through the singular pose (E, A and B on
// one line) is refused and the shafts stop, as the linkage would lock. Thread-safe: the board's
// loop steps it, the test reads it and moves the hand.
#pragma once

#include <array>
#include <cstdint>
#include <mutex>
#include <numbers>
#include <optional>

#include "mechanics.h"

namespace hapticd::reference {

struct PantographGeometry {
  double l = 0.05, L = 0.07, d = 0.02;  // m, Pantograph.cpp's constructor
};

struct PantographPose {
  Vec2 effector;                              // m, Pantograph.cpp's frame
  std::array<std::array<double, 2>, 2> jv{};  // jv[row x|y][column theta1|theta2], m/rad
};

class PantographPlant {
 public:
  // 140 and 40 degrees: the effector at (d/2, 0.0828), the middle of the workspace.
  static constexpr std::array<double, 2> kStartAngles = {140.0 * std::numbers::pi / 180.0,
                                                         40.0 * std::numbers::pi / 180.0};

  explicit PantographPlant(std::array<JointMechanics, 2> joints = {},
                           std::array<double, 2> angles = kStartAngles,
                           PantographGeometry geometry = {});

  // The effector and Jacobian at `angles` (rad); none out of reach or at the singular pose.
  static std::optional<PantographPose> forward(const PantographGeometry& g,
                                               std::array<double, 2> angles);
  // The angles (rad) that put the effector at `effector`, elbows out (A left of motor 1, B right
  // of motor 2, as the 2DIY is built); none out of reach.
  static std::optional<std::array<double, 2>> inverse(const PantographGeometry& g, Vec2 effector);

  // The board's loop: `dt` seconds under the shaft torques `motor` (N m) and the hand.
  void step(double dt, std::array<double, 2> motor);
  // The test: from now on a hand pushing the effector with `push_N` (N, Haply's frame) and
  // resisting its motion with `damping` (N s/m).
  void hand(Vec2 push_N, double damping);

  std::array<double, 2> angles() const;      // rad
  std::array<double, 2> velocities() const;  // rad/s
  Vec2 effector() const;                     // m
  Vec2 effector_velocity() const;            // m/s
  std::array<double, 2> motor() const;       // the shaft torques of the last step, N m
  std::uint64_t locked_steps() const;        // steps refused at the edge of the workspace
  const PantographGeometry& geometry() const { return g_; }

 private:
  const PantographGeometry g_;
  const std::array<JointMechanics, 2> joints_;
  mutable std::mutex m_;
  std::array<double, 2> theta_, omega_{}, motor_{};
  PantographPose pose_;
  Vec2 push_;
  double hand_damping_ = 0.0;
  std::uint64_t locked_ = 0;
};

}  // namespace hapticd::reference
