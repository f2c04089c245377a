// Walls in task space (docs/kinematics.md, walls in task space): each wall a half-space, a point
// p and a unit normal n pointing into it, with its own contact law along n. Its law is the
// one-joint law of controller.h run on the coordinate s = n . (x - p) (a wall at 0 occupying
// s > 0), so every wall keeps what one axis has: the filters, the coupling, the delay, no_pull,
// arming and the runaway guard. An attractor (a spring-damper to its point p) runs the same law
// with its contact never open along each task axis e_k, on s_k = e_k . (x - p): each of those is
// a channel, as a wall's normal is its one channel. The channels' forces add in task space, map
// to the joints through J^T, and are saturated by one factor for every joint, so the force keeps
// its direction.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "control/controller.h"
#include "kinematics/pose.h"
#include "kinematics/saturation.h"

namespace hapticd::control {

using config::kMaxWalls;
// A wall is one channel, an attractor one per task axis.
inline constexpr std::size_t kMaxChannels = 3 * kMaxWalls;

struct WallGeometry {
  kinematics::Vec3 point = kinematics::Vec3::Zero();   // on the wall's face (m), first m entries
  kinematics::Vec3 normal = kinematics::Vec3::Zero();  // unit, into the wall; zero: an attractor
  int attractor_axes = 0;  // an attractor's task axes (1..3), each a channel; 0 for a wall
  // An attractor's largest force (N, its task force's norm); its channels are scaled together.
  double max_force = std::numeric_limits<double>::infinity();
  bool attractor() const noexcept { return attractor_axes > 0; }
};

struct SceneStep {
  std::array<ControlOutput, kMaxChannels> channels{};  // each channel's step (its coordinate)
  std::size_t count = 0;                               // channels stepped
  kinematics::Vec3 force = kinematics::Vec3::Zero();   // sum of the walls' forces (task, N)
  kinematics::Vec3 tau = kinematics::Vec3::Zero();     // J^T force, saturated (joints)
  kinematics::SaturationStatus saturation = kinematics::SaturationStatus::kWithin;
  double scale = 1.0;         // what the joint saturation multiplied tau by
  std::uint32_t flags = 0;    // ControlFlag bits of every channel, or-ed
  std::uint32_t contact = 0;  // bit i: wall i acts (an attractor always does)
  bool pose_ok = true;        // false: the pose was not kinematics::Status::kOk, zero torque
};

class Scene {
 public:
  // Not RT-safe: builds each channel's controller (its delay line). `laws[i]` is wall i's law
  // along its normal (an attractor's along each axis), with wall_position 0 and normal +1
  // (control_law.h). `max_move`: how far (m) a wall's point may slide in one tick towards its
  // place after a swap (continue_from; safety.max_wall_speed T). Throws std::invalid_argument
  // for more than kMaxWalls walls, sizes that differ, a wall's normal that is not unit (within
  // 1e-9) or not finite, an attractor of more than 3 axes or whose max_force is not positive,
  // or a max_move that is not positive.
  Scene(std::span<const WallGeometry> geometry, std::span<const ControlLaw> laws,
        double max_move = std::numeric_limits<double>::infinity());

  // RT-safe: called every tick. Steps every wall on the task position of `pose` and maps the
  // sum through its Jacobian; `limit` holds each joint's force limit. A pose that is not kOk,
  // a non-finite torque or limit gives zero torque (kControlNonFinite for the latter, for the
  // loop to fault on); the walls are stepped all the same, so their histories stay whole.
  SceneStep step(const kinematics::Pose& pose, const kinematics::Vec3& limit) noexcept;

  // The two halves of step(), for a loop that adds to each channel's force in between (the
  // passivity controller along each). RT-safe: called every tick. step_walls steps every
  // channel (out.channels, flags, contact, pose_ok, their summed force); map puts `commands`
  // (one per channel, along its direction) and `added` (a task force of a client's, N) through
  // J^T and the saturation into out.force and out.tau.
  void step_walls(const kinematics::Pose& pose, SceneStep& out) noexcept;
  void map(const kinematics::Pose& pose, std::span<const double> commands,
           const kinematics::Vec3& limit, SceneStep& out,
           const kinematics::Vec3& added = kinematics::Vec3::Zero()) const noexcept;
  // RT-safe. Channel c's law; the law of wall i's (first) channel.
  const ControlLaw& law(std::size_t c) const noexcept { return channels_[c].law(); }
  const ControlLaw& wall_law(std::size_t i) const noexcept { return law(first_[i]); }

  // RT-safe. Every wall's filters cleared and disarmed, every attractor fresh (as at
  // construction).
  void reset() noexcept;
  // RT-safe: a swap at a tick boundary. Wall i goes on from `from`'s wall continues[i] (its
  // filters, delay line and arming: Controller::continue_from) and from where that wall's
  // point was, sliding to its own at most max_move a tick; a wall with -1, or whose normal
  // changed, starts afresh in its place (unarmed while the device is inside it, as at
  // start-up), as does one whose kind or axes changed. The last task position carries over.
  // An attractor that starts afresh (built, reset, new in a swap) starts at the device's
  // position and slides to its point at most max_move a tick: it never yanks the device, nor
  // kicks its damping, however far its point is.
  void continue_from(const Scene& from, std::span<const int> continues) noexcept;

  // RT-safe: at a tick boundary (a client's move, loop/wall_moves.h). Wall i's place becomes
  // `place`; its point slides there at most max_move a tick, its law and history going on.
  // Ignored for an i past the walls (the move named a wall a swap removed meanwhile).
  void move_to(std::size_t i, const kinematics::Vec3& place) noexcept;

  std::size_t size() const noexcept { return walls_; }
  std::size_t channels() const noexcept { return channels_.size(); }
  // Where wall i is now (its point on the way to its place after a swap).
  const WallGeometry& geometry(std::size_t i) const noexcept { return geometry_[i]; }
  // Channel c's wall, and its direction (the wall's normal, or an attractor's axis e_k).
  std::size_t wall_of(std::size_t c) const noexcept { return wall_of_[c]; }
  const kinematics::Vec3& direction(std::size_t c) const noexcept { return direction_[c]; }
  // Wall i's first channel; its channels are first_channel(i) up to first_channel(i + 1).
  std::size_t first_channel(std::size_t i) const noexcept { return first_[i]; }

 private:
  // RT-safe. Channel c's coordinate s = d . (x - p) at the task position x.
  double coordinate(std::size_t c, const kinematics::Vec3& x) const noexcept {
    return direction_[c].dot(x - geometry_[wall_of_[c]].point);
  }

  // RT-safe. Each wall's point a step of at most max_move_ nearer its place.
  void slide() noexcept;
  // RT-safe. Every fresh attractor's point to `x`, to slide to its place from there.
  void start_attractors(const kinematics::Vec3& x) noexcept;
  // RT-safe. Attractor i's channels scaled together to its max_force.
  void limit_attractor(std::size_t i, SceneStep& out) const noexcept;

  std::array<WallGeometry, kMaxWalls> geometry_{};
  std::array<kinematics::Vec3, kMaxWalls> place_{};  // each wall's configured point
  std::array<std::size_t, kMaxWalls + 1> first_{};   // each wall's first channel
  std::array<std::size_t, kMaxChannels> wall_of_{};
  std::array<kinematics::Vec3, kMaxChannels> direction_{};
  std::size_t walls_ = 0;
  double max_move_;
  bool sliding_ = false;                 // a wall is not at its place yet (after a swap)
  std::array<bool, kMaxWalls> fresh_{};  // an attractor that has not yet started from x
  bool any_fresh_ = false;               // any fresh_ set (the usual tick: none)
  bool attractors_ = false;              // any wall an attractor
  std::vector<Controller> channels_;     // built once, never resized
  kinematics::Vec3 last_x_ = kinematics::Vec3::Zero();  // the last finite task position
};

// Not RT-safe. Wall `w`'s law along its normal: make_control_law of its own section on the
// coordinate s = n . (x - p) (a wall at 0 occupying s > 0), limited by the joints alone. An
// attractor's, along each axis: its contact never opens, it acts at once (no arming), and no
// runaway guard (it pulls from anywhere by design; its max_force and the joints' bound it).
ControlLaw task_wall_law(const config::Config& cfg, const config::TaskWallConfig& w);

// Not RT-safe. The scene of cfg's `walls` (none for a device of one joint): each wall's law is
// task_wall_law of its own section, on its coordinate along the normal (an attractor's axes).
Scene make_scene(const config::Config& cfg);

}  // namespace hapticd::control
