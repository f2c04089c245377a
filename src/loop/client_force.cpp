#include "loop/client_force.h"

#include <algorithm>

namespace hapticd::loop {

void ClientForce::offer(const kinematics::Vec3& force, std::int64_t received_ns) noexcept {
  const std::uint64_t was = sequence_.load(std::memory_order_relaxed);
  sequence_.store(was + 1, std::memory_order_relaxed);
  // Each a release (no fence: ThreadSanitizer does not follow fences): a reader that sees one
  // sees the odd sequence before it.
  for (int a = 0; a < 3; ++a) offered_[a].store(force[a], std::memory_order_release);
  received_ns_.store(received_ns, std::memory_order_release);
  sequence_.store(was + 2, std::memory_order_release);
}

void ClientForce::restart() noexcept {
  command_.setZero();  // an arming starts with no client force: the client sends again
  energy_ = limits_.energy_j;
  started_ = true;
  last_force_.setZero();
  last_placed_ = false;
  limited_ = false;
}

kinematics::Vec3 ClientForce::step(std::int64_t now_ns) noexcept {
  if (!started_) restart();
  const std::uint64_t before = sequence_.load(std::memory_order_acquire);
  if (before != taken_ && (before & 1u) == 0) {
    kinematics::Vec3 f;
    // Each an acquire: the second look at the sequence comes after them.
    for (int a = 0; a < 3; ++a) f[a] = offered_[a].load(std::memory_order_acquire);
    const std::int64_t at = received_ns_.load(std::memory_order_acquire);
    if (sequence_.load(std::memory_order_relaxed) == before) {  // else torn: the next tick
      command_ = f.allFinite() ? f : kinematics::Vec3::Zero();
      received_ = at;
      taken_ = before;
    }
  }
  limited_ = !(energy_ > 0.0);
  if (limited_ || command_.isZero(0.0)) return kinematics::Vec3::Zero();
  const std::int64_t age = now_ns - received_ - limits_.hold_ns;
  if (age <= 0) return command_;
  if (age >= limits_.ramp_ns) return kinematics::Vec3::Zero();
  return command_ * (1.0 - static_cast<double>(age) / static_cast<double>(limits_.ramp_ns));
}

void ClientForce::acted(const kinematics::Vec3& force, const kinematics::Vec3& x,
                        bool placed) noexcept {
  // The work the force that acted over the last period did on the device as it moved.
  if (placed && last_placed_) energy_ -= last_force_.dot(x - last_x_);
  energy_ = std::min(energy_ + limits_.energy_j * limits_.period_s, limits_.energy_j);
  last_force_ = force;
  if (placed) last_x_ = x;
  last_placed_ = placed;
}

}  // namespace hapticd::loop
