// Several simulated drives on one bus, one per node of device.can.nodes, moving the joints of
// one simulated mechanism (sim/mechanism.h: the device's kinematics, each joint's mass and
// damping, device.sim's hand in task space): `hapticd run --loopback` and `hapticd peer` of a
// gantry. The bus end (the driver's socketpair, or a real interface) reaches each drive through
// a socketpair of its own: every frame the master sends goes to every drive, as a CAN bus does,
// and every frame a drive sends goes on the bus. It is one loopback peer: its service()
// services every drive until nothing moves, so a PeerRunner's wait_idle() waits for every
// drive's answer.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "config/config.h"
#include "drivers/can/can_socket.h"
#include "drivers/io/unique_fd.h"
#include "sim/mechanism.h"
#include "sim/peers/can/can_peer_base.h"
#include "sim/peers/loopback_peer.h"

namespace hapticd::sim {

class CanBusPeer final : public LoopbackPeer {
 public:
  // Not RT-safe. One drive of cfg's profile per node, joint i at nodes[i]. Throws
  // std::invalid_argument for a mechanism (device.sim) that cannot be simulated.
  CanBusPeer(const config::Config& cfg, drivers::can::CanSocket bus, bool realtime);

  void service() override;
  int fd() const noexcept override { return bus_.fd(); }
  int service_interval_ms() const noexcept override;
  // The largest force any joint's motor puts on the mechanism, and whether any is on: what
  // the hand can feel.
  double applied_force() const noexcept override;
  bool output_on() const noexcept override;
  // The first drive's axis of its own: the mechanism is joint_plant().
  const Plant& plant() const noexcept override { return drives_.front()->plant(); }
  const JointPlant* joint_plant() const noexcept override { return &mechanism_->plant(); }
  // Every drive produces `fault` (one of them faulting is the tests' drive(i).inject).
  bool inject(PeerFault fault) noexcept override;

  std::size_t nodes() const noexcept { return drives_.size(); }
  // The drive at nodes[i], for the tests: its own faults, its amplifier.
  CanPeerBase& drive(std::size_t i) noexcept { return *drives_[i]; }
  // Any thread: the frames the master sent with this 11-bit id so far.
  std::uint64_t frames_from_master(std::uint32_t id) const noexcept {
    return sent_[id & 0x7FF].load(std::memory_order_relaxed);
  }

 private:
  // Moves every message waiting on `from` to each of `to`; true when any moved. Counts the
  // master's frames (from the bus end).
  bool forward(int from, std::span<const int> to);

  std::unique_ptr<Mechanism> mechanism_;
  drivers::can::CanSocket bus_;
  std::vector<io::UniqueFd> drive_ends_;  // the bus's end of each drive's socketpair
  std::vector<int> drive_fds_;            // their descriptors, to forward to
  std::vector<std::unique_ptr<CanPeerBase>> drives_;
  std::array<std::atomic<std::uint64_t>, 2048> sent_{};
};

}  // namespace hapticd::sim
