// The device of a configuration of several CAN nodes (device.can.nodes) against the simulated
// bus hapticd's --loopback runs (sim/peers/can/can_bus_peer.h): one simulated drive per node,
// all moving one mechanism.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "alloc_counter.h"
#include "can_rig.h"
#include "drivers/can/can_settings.h"
#include "sim/peers/can/can_bus_peer.h"

namespace hapticd::drivers::can::testing {

// The device of cfg (device.can.nodes) against one simulated drive per node.
struct NodesRig {
  explicit NodesRig(const config::Config& c) : cfg(c) {
    auto [mine, theirs] = io::seqpacket_pair();
    auto fd = std::make_shared<io::UniqueFd>(std::move(mine));
    device = make_can_device(cfg, [fd] { return CanSocket::adopt(std::move(*fd), "pair"); });
    hub = std::make_unique<sim::CanBusPeer>(cfg, CanSocket::adopt(std::move(theirs), "the bus"),
                                            false);
    runner = std::make_unique<sim::PeerRunner>(*hub);
  }
  ~NodesRig() {
    if (device) device->close();
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
  std::unique_ptr<sim::CanBusPeer> hub;
  std::unique_ptr<sim::PeerRunner> runner;
};

}  // namespace hapticd::drivers::can::testing
