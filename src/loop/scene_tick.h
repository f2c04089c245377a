// The tick of a device of several joints as a value, as tick.h is for one: checked joint
// positions in, the joint torques and the record's control fields out; no clock, no device, no
// ring. ServoLoop::run calls it on what the device read, `hapticd replay` on what a tick log
// recorded, so a log's torques come back bit for bit by construction (docs/kinematics.md, the
// loop at several joints).
//
// Each tick: the pose x = fk(q) (the previous x the delta's guess); every channel stepped on its
// coordinate s_i = n_i . (x - p_i) (an attractor's axes: e_k . (x - p)); each channel's passivity
// observer (control/passivity_observer.h on s_i, crediting the least damping the device has along
// n_i over the workspace, the gate's b_n) and, in damp mode, its damping along n_i; the walls'
// forces through J^T, saturated by one factor. A pose that is not ok is a fault with zero torque.
// The runaway guard is one joint's (controller.h) on the deepest wall: saturated, deeper than the
// walls can hold, and not slowing. Deeper than they can hold: the saturation scaled the walls'
// force below 1 / config::kRunawayMargin of what they asked (in one dimension exactly the
// penetration kRunawayMargin max_force / K), or past an explicit safety.max_penetration.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "control/passivity_observer.h"
#include "control/scene.h"
#include "kinematics/kinematics.h"
#include "loop/law_swap.h"
#include "loop/sample_check.h"
#include "telemetry/tick_record.h"

namespace hapticd::loop {

struct JointInput {
  kinematics::Vec3 q = kinematics::Vec3::Zero();  // each joint's position (held when stale)
  bool fresh = true;                              // new measurements, none held or stale
  std::uint32_t periods = 1;                      // sample periods since the previous tick
  // A client's commanded force this tick (task space, N; loop/client_force.h).
  kinematics::Vec3 client_force = kinematics::Vec3::Zero();

  // RT-safe. What a log recorded of a tick the loop stepped (kFlagStepped).
  static JointInput recorded(const telemetry::TickRecord& r, std::uint32_t periods) noexcept {
    JointInput in;
    in.q = {r.position, r.joint_position[0], r.joint_position[1]};
    in.client_force = {r.client_force[0], r.client_force[1], r.client_force[2]};
    in.fresh = (r.flags & (telemetry::kFlagStale | telemetry::kFlagHeld)) == 0;
    in.periods = periods;
    return in;
  }
};

struct JointCommand {
  kinematics::Vec3 tau = kinematics::Vec3::Zero();      // each joint's torque to write
  std::array<double, control::kMaxChannels> channel{};  // each channel's force along it
  std::array<double, control::kMaxChannels> added{};    // the passivity controller's part of it
  double scale = 1.0;                                   // the joint saturation's factor
  kinematics::Vec3 force = kinematics::Vec3::Zero();    // the task force that acts (N), scaled
  bool non_finite = false;  // a non-finite force or torque: the loop faults
  bool runaway = false;     // a wall's runaway guard tripped: the loop faults
  bool pose_fault = false;  // the pose was not ok (rec.pose_status says why): the loop faults

  // RT-safe. Any of the three: nothing but zero may be written.
  bool faulted() const noexcept { return non_finite || runaway || pose_fault; }
};

// What a scene of several joints renders: its walls and an observer per channel (a wall's
// normal, an attractor's axes; control/scene.h), built off the RT thread, and swapped in whole at a
// tick boundary by a live reload (SceneSwap). What the walls that a swap ended had observed stays
// in the run's totals (`ended`).
struct SceneWalls {
  // Not RT-safe. Throws std::invalid_argument when `observers` does not hold one set of
  // parameters per channel of `scene`.
  SceneWalls(std::unique_ptr<control::Scene> scene,
             const std::vector<control::ObserverParams>& observers);

  // RT-safe: taken at a tick boundary. Wall i goes on from `running`'s wall continues[i]
  // (its filters and its observers' energies; -1: a new wall, which starts afresh), and the
  // observations of `running`'s channels that no channel continues join `ended`.
  void continue_from(SceneWalls& running) noexcept;

  // The walls' observations together: energies and works add, each minimum adds into a
  // bound below the sum's, the most ticks any wall had below zero, the largest damping.
  struct Totals {
    double energy_j = 0.0;
    double min_energy_j = 0.0;
    double wall_work_j = 0.0;
    double damping_work_j = 0.0;
    std::uint64_t negative_ticks = 0;
    double max_damping = 0.0;
    void add(const control::PassivityObserver& o) noexcept;
  };
  // RT-safe. Every wall's, the ended ones' included.
  Totals totals() const noexcept;

  std::unique_ptr<control::Scene> scene;
  std::vector<control::PassivityObserver> observers;  // one per channel
  std::array<int, config::kMaxWalls> continues;       // set before the offer; -1: a new wall
  Totals ended;
};

// A scene's new walls for the loop: a live reload at several joints.
using SceneSwap = TickSwap<SceneWalls>;

// What the scene's tick works on, built before the loop (not RT-safe to build).
struct SceneState {
  SceneState(const kinematics::Kinematics& kinematics, SceneWalls& walls,
             const kinematics::Vec3& limit);

  // RT-safe. A new run: no position, nothing in flight (the energies go on).
  void restart() noexcept;

  kinematics::Kinematics kinematics;
  SceneWalls* walls;       // what is rendered now; a reload swaps it (owned by the caller)
  kinematics::Vec3 limit;  // each joint's force limit
  kinematics::Vec3 guess;  // the last task position (the delta's start)
  // The deepest wall's penetration over the runaway guard's two windows, newest first.
  std::array<double, 2 * control::Controller::kRunawayWindow> deepest{};
  std::size_t stepped = 0;  // ticks stepped since restart (the guard waits for its windows)
};

// RT-safe: called every tick with positions. Fills the record's control fields (joint
// positions, task position, the deepest wall's penetration, velocity and force, contact bits,
// pose status, the observers' energy and damping, kFlagStepped and the walls' flags).
JointCommand step_scene_tick(SceneState& st, const JointInput& in,
                             telemetry::TickRecord& rec) noexcept;

// RT-safe: called every tick with what was written (`c`, or nothing after a fault): the
// joints' torques in the record, and each wall's share of them for its observer.
void end_scene_tick(SceneState& st, const JointCommand* c, telemetry::TickRecord& rec) noexcept;

}  // namespace hapticd::loop
