// The device a run drives, built through the driver registry: the driver for real hardware,
// or (`--loopback`, and always for the sim) the driver wired to its simulated peer, the peer
// on its own thread, and the driver paced by the peer (sim/peers/peer_runner.h says why).
// Owns them in the order that tears them down safely: the device is closed (output off, its
// transport closed) before the peer's thread stops.
#pragma once

#include <memory>
#include <string>

#include "config/config.h"
#include "drivers/device.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::service {

class DeviceSession {
 public:
  // Not RT-safe. Builds the device (unconfigured). Throws config::ConfigError for a loopback
  // that cannot be simulated, DeviceError for a driver that cannot run here.
  DeviceSession(const config::Config& cfg, bool loopback, bool realtime);
  ~DeviceSession();  // closes the device, then stops the peer
  DeviceSession(const DeviceSession&) = delete;
  DeviceSession& operator=(const DeviceSession&) = delete;

  Device& device() { return *device_; }
  const Device& device() const { return *device_; }
  const wiring::DriverEntry& driver() const { return driver_; }
  // The simulated device behind a loopback (null for real hardware).
  sim::LoopbackPeer* peer() { return peer_.get(); }
  // Not RT-safe. Closes the device and stops the peer's thread; afterwards peer() may be
  // read without racing it. Idempotent.
  void shut_down() noexcept;
  // Why the peer failed, if it did ("" otherwise); after shut_down().
  std::string peer_error() const;

 private:
  const wiring::DriverEntry& driver_;
  std::unique_ptr<sim::LoopbackPeer> peer_;
  std::unique_ptr<sim::PeerRunner> runner_;
  std::unique_ptr<Device> device_;
  std::string peer_error_;
};

}  // namespace hapticd::service
