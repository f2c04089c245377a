// A force a client commands directly (servo_cf, docs/clients.md): handed to the RT thread
// through a sequence lock, and rendered with the walls' force (one saturation for both; on a
// device of one joint, along the joint once the direction check armed the wall). What keeps it
// safe:
//   - its size: the control thread saturates it to safety.client_force_limit (and says so);
//   - its client's silence: it holds safety.client_force_hold_ms after it arrived, then ramps to
//     zero over safety.client_force_ramp_ms; a client that leaves takes it with it at once;
//   - its energy: an observer of the work it does on the device, E_k = E_{k-1} - f . dx over each
//     period (the force that acted, the motion under it), refilled at E_max per second up to
//     E_max = safety.client_force_energy_j. Below zero the force is off; so over any t seconds
//     it puts at most E_max (1 + t) into the device, and one period's work more (the period
//     that took E below zero), whatever the client sends.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "kinematics/pose.h"

namespace hapticd::loop {

struct ClientForceLimits {
  double max_force = 0.0;    // N, the norm it is saturated to (0: no client force)
  std::int64_t hold_ns = 0;  // how long a command holds
  std::int64_t ramp_ns = 0;  // how long it then takes to fade to zero
  double energy_j = 0.0;     // E_max (J)
  double period_s = 0.001;   // the loop's T (the refill per tick is E_max T)
};

class ClientForce {
 public:
  explicit ClientForce(const ClientForceLimits& limits) noexcept : limits_(limits) {}

  // Not RT-safe; one offering thread at a time. The force to render from now (N, task space,
  // already saturated, finite), received at `received_ns` (CLOCK_MONOTONIC).
  void offer(const kinematics::Vec3& force, std::int64_t received_ns) noexcept;

  // RT-safe: called every tick, first. This tick's force: the newest offer, faded by its age
  // at `now_ns`, off while the observer's energy is not positive.
  kinematics::Vec3 step(std::int64_t now_ns) noexcept;
  // RT-safe: called every tick, last. What of it acted (the saturation's share; zero after a
  // fault) and the task position the tick had (none: `placed` false): the observer's work.
  void acted(const kinematics::Vec3& force, const kinematics::Vec3& x, bool placed) noexcept;
  // RT-safe. A new run: no force until the client sends one again, the energy full.
  void restart() noexcept;

  double energy_j() const noexcept { return energy_; }
  bool limited() const noexcept { return limited_; }  // the observer held it off this tick

 private:
  ClientForceLimits limits_;
  std::atomic<std::uint64_t> sequence_{0};  // odd while an offer is written
  std::array<std::atomic<double>, 3> offered_{};
  std::atomic<std::int64_t> received_ns_{0};
  // The RT thread's alone.
  std::uint64_t taken_ = 0;
  kinematics::Vec3 command_ = kinematics::Vec3::Zero();
  std::int64_t received_ = 0;
  double energy_ = 0.0;
  bool started_ = false;
  bool limited_ = false;
  kinematics::Vec3 last_force_ = kinematics::Vec3::Zero();  // what acted over the last period
  kinematics::Vec3 last_x_ = kinematics::Vec3::Zero();
  bool last_placed_ = false;
};

}  // namespace hapticd::loop
