// Several simulated drives on one bus, as the CAN tests of device.can.nodes use them: the
// device's end of a socketpair goes to a hub that gives every frame the device sends to every
// drive (each on a socketpair of its own, each playing one node of the configuration) and
// every frame a drive sends to the device, as a CAN bus does, counting the frames on the wire.
// The hub is one loopback peer: it services its drives in its own service(), so a PeerRunner's
// wait_idle() waits for every drive's answer.
#pragma once

#include <linux/can.h>
#include <sys/socket.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "alloc_counter.h"
#include "can_rig.h"
#include "drivers/can/can_settings.h"

namespace hapticd::drivers::can::testing {

class NodesBusHub final : public sim::LoopbackPeer {
 public:
  // One simulated drive per node of cfg's device.can.nodes.
  NodesBusHub(const config::Config& cfg, io::UniqueFd bus_end) : bus_(std::move(bus_end)) {
    const CanSettings& s = can_settings(cfg);
    for (std::size_t i = 0; i < s.nodes.size(); ++i) {
      config::Config one = cfg;
      one.device.settings = std::make_shared<CanSettings>(single_node(s, i));
      auto [hub_end, drive_end] = io::seqpacket_pair();
      drive_ends_.push_back(std::move(hub_end));
      drives_.push_back(
          sim::make_can_peer(one, CanSocket::adopt(std::move(drive_end), "node peer"), false));
    }
  }

  void service() override {
    for (bool moved = true; moved;) {
      moved = false;
      std::array<unsigned char, 64> buf{};
      ssize_t n = 0;
      while ((n = ::recv(bus_.get(), buf.data(), buf.size(), MSG_DONTWAIT)) > 0) {
        count(buf.data(), n);
        for (const io::UniqueFd& d : drive_ends_) {
          [[maybe_unused]] const ssize_t w =
              ::send(d.get(), buf.data(), static_cast<std::size_t>(n), MSG_NOSIGNAL);
        }
        moved = true;
      }
      for (const auto& drive : drives_) drive->service();
      for (const io::UniqueFd& d : drive_ends_) {
        while ((n = ::recv(d.get(), buf.data(), buf.size(), MSG_DONTWAIT)) > 0) {
          [[maybe_unused]] const ssize_t w =
              ::send(bus_.get(), buf.data(), static_cast<std::size_t>(n), MSG_NOSIGNAL);
          moved = true;
        }
      }
    }
  }
  int fd() const noexcept override { return bus_.get(); }
  double applied_force() const noexcept override { return drives_.front()->applied_force(); }
  bool output_on() const noexcept override { return drives_.front()->output_on(); }
  const sim::Plant& plant() const noexcept override { return drives_.front()->plant(); }
  bool inject(sim::PeerFault) noexcept override { return false; }

  sim::CanPeerBase& drive(std::size_t i) { return dynamic_cast<sim::CanPeerBase&>(*drives_[i]); }
  // Any thread: frames the device sent with this 11-bit id so far.
  std::uint64_t sent_with_id(std::uint32_t id) const {
    const std::lock_guard lock(mutex_);
    const auto it = sent_.find(id);
    return it == sent_.end() ? 0 : it->second;
  }

 private:
  void count(const unsigned char* data, ssize_t n) {
    if (n != static_cast<ssize_t>(sizeof(can_frame))) return;
    can_frame f{};
    std::memcpy(&f, data, sizeof f);
    const std::lock_guard lock(mutex_);
    ++sent_[f.can_id & CAN_SFF_MASK];
  }

  io::UniqueFd bus_;
  std::vector<io::UniqueFd> drive_ends_;
  std::vector<std::unique_ptr<sim::LoopbackPeer>> drives_;
  mutable std::mutex mutex_;
  std::map<std::uint32_t, std::uint64_t> sent_;
};

// The device of cfg (device.can.nodes) against one simulated drive per node.
struct NodesRig {
  explicit NodesRig(const config::Config& c) : cfg(c) {
    auto [mine, theirs] = io::seqpacket_pair();
    auto fd = std::make_shared<io::UniqueFd>(std::move(mine));
    device = make_can_device(cfg, [fd] { return CanSocket::adopt(std::move(*fd), "pair"); });
    hub = std::make_unique<NodesBusHub>(cfg, std::move(theirs));
    runner = std::make_unique<sim::PeerRunner>(*hub);
  }
  ~NodesRig() {
    device->close();
    runner->stop();
  }
  // One tick as the loop does it: read every joint, then write every joint's force, then wait
  // for the drives to answer.
  IoStatus tick(std::span<const double> forces, std::span<PositionSample> samples) {
    const IoStatus r = device->read(samples);
    if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) {
      runner->wait_idle();
      return r;
    }
    const IoStatus w = device->write(forces);
    runner->wait_idle();
    return w == IoStatus::kOk ? r : w;
  }

  // `n` ticks of `forces` inside an allocation count: how many read a new sample on every
  // joint, what read and write allocated, and the first status that was neither kOk nor
  // kNoNewData (kOk when none was; the ticks stop there).
  struct Run {
    int fresh = 0;
    std::uint64_t allocations = 0;
    IoStatus failure = IoStatus::kOk;
  };
  Run ticks(std::span<const double> forces, std::span<PositionSample> samples, int n) {
    Run run;
    const hapticd::testing::AllocationScope scope;
    for (int i = 0; i < n && run.failure == IoStatus::kOk; ++i) {
      const IoStatus r = tick(forces, samples);
      if (r != IoStatus::kOk && r != IoStatus::kNoNewData) run.failure = r;
      run.fresh += r == IoStatus::kOk ? 1 : 0;
    }
    run.allocations = scope.count();
    return run;
  }

  config::Config cfg;
  std::unique_ptr<Device> device;
  std::unique_ptr<NodesBusHub> hub;
  std::unique_ptr<sim::PeerRunner> runner;
};

}  // namespace hapticd::drivers::can::testing
