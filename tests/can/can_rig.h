// A CAN device and its simulated drive over a socketpair, the drive on its own thread, as the
// CAN tests use them: loaded from an example configuration with overrides, in freerun.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "config/config_loader.h"
#include "drivers/can/can_driver.h"
#include "sim/peers/can/can_peer_base.h"
#include "sim/peers/can/can_peer_entry.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers::can::testing {

inline config::Config load_example(const std::string& name, std::vector<std::string> sets = {},
                                   bool freerun = true) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/config/" + name;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> overrides;
  // A drive in the test's own process answers at once unless the host holds its thread: under
  // a loaded host (two emulators and a build) configure's 100 ms SDO wait of the examples ran
  // out. First, so that a test of the time-out sets its own.
  if (freerun) overrides.push_back(config::parse_override("device.can.sdo_timeout_ms=2000"));
  if (freerun) sets.push_back("loop.clock=freerun");
  for (const std::string& s : sets) overrides.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), path, overrides, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

// One of the driver's counters, by name, as the run summary and `hapticctl status` list it
// (Device::counters); a counter the driver does not have fails the test.
inline const base::Counter& counter(const Device& device, std::string_view name) {
  for (const base::Counter& c : device.counters()) {
    if (c.name() == name) return c;
  }
  ADD_FAILURE() << "the can driver has no counter " << name;
  static const base::Counter none("none", base::CounterKind::kCount, "");
  return none;
}

struct CanRig {
  explicit CanRig(const config::Config& c)
      : cfg(c), pair(wiring::find_driver("can").make_loopback(c)), runner(*pair.peer) {}
  // The device configured one way, the simulated drive another (a firmware the driver must
  // find out about).
  // `realtime_peer`: the drive keeps its wall-clock watchdogs, as `hapticd peer` on a bus does.
  CanRig(const config::Config& device_cfg, const config::Config& peer_cfg,
         bool realtime_peer = false)
      : cfg(device_cfg), pair(split(device_cfg, peer_cfg, realtime_peer)), runner(*pair.peer) {}
  static wiring::Loopback split(const config::Config& device_cfg, const config::Config& peer_cfg,
                                bool realtime_peer) {
    auto [mine, theirs] = io::seqpacket_pair();
    auto fd = std::make_shared<io::UniqueFd>(std::move(mine));
    wiring::Loopback l;
    l.device =
        make_can_device(device_cfg, [fd] { return CanSocket::adopt(std::move(*fd), "pair"); });
    l.peer = sim::make_can_peer(peer_cfg, CanSocket::adopt(std::move(theirs), "pair peer"),
                                realtime_peer);
    return l;
  }
  ~CanRig() {
    if (pair.device) pair.device->close();
    runner.stop();
  }
  Device& device() { return *pair.device; }
  sim::CanPeerBase& peer() { return dynamic_cast<sim::CanPeerBase&>(*pair.peer); }
  void settle() { runner.wait_idle(); }
  // One tick as the loop does it: read, then write, then wait for the drive to answer.
  IoStatus tick(double force, PositionSample& s) {
    const IoStatus r = device().read(s);
    if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) {
      settle();
      return r;
    }
    const IoStatus w = device().write(force);
    settle();
    return w == IoStatus::kOk ? r : w;
  }
  // Ticks until a fault (or `limit` ticks); the fault status, or kOk.
  IoStatus run_until_fault(double force, int limit) {
    PositionSample s;
    for (int i = 0; i < limit; ++i) {
      const IoStatus r = tick(force, s);
      if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return r;
    }
    return IoStatus::kOk;
  }

  config::Config cfg;
  wiring::Loopback pair;
  sim::PeerRunner runner;
};

}  // namespace hapticd::drivers::can::testing
