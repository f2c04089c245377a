// The driver registry (docs/devices.md), in the composition root: each driver this build has,
// its device (drivers/<name>/, drivers/device_entry.h) joined by driver name with its
// simulated device (sim/peers/<name>/, sim/peers/peer_entry.h). `check`, `verify` and `run`
// all analyse the delay declared here, so they analyse the same loop. Adding a driver touches
// its own folders, one line of registry.cpp and HAPTICD_DRIVER_NAMES (CMakeLists.txt).
#pragma once

#include <memory>
#include <span>
#include <string_view>

#include "config/config.h"
#include "config/driver_schema.h"
#include "drivers/device.h"
#include "drivers/device_entry.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_entry.h"

namespace hapticd::wiring {

// A driver and the simulated device it talks to (hapticd run --loopback, the conformance
// suite): the driver's own protocol code against its peer over a socketpair.
struct Loopback {
  std::unique_ptr<Device> device;
  std::unique_ptr<sim::LoopbackPeer> peer;  // never null
};

// A driver: what its device half says (name, section, declared delay, hardware, notes,
// listing) and its simulated device.
struct DriverEntry : drivers::DeviceEntry {
  sim::PeerEntry peer;
  // Not RT-safe. The pair built in one process without a socketpair: the sim, whose device is
  // its own peer. Null for a driver with a transport.
  Loopback (*make_in_process)(const config::Config& cfg) = nullptr;

  // Not RT-safe. The device wired to its simulated device, both unconfigured. Throws
  // config::ConfigError for a plant (device.sim) that cannot be simulated.
  Loopback make_loopback(const config::Config& cfg) const;
};

// Every driver of this build, the sim first.
std::span<const DriverEntry> registered_drivers();
// Throws DeviceError naming the drivers there are when `name` is not one of them.
const DriverEntry& find_driver(std::string_view name);
// What the config loader needs to validate device.driver and read the driver's section.
const config::DriverSchemas& driver_schemas();

}  // namespace hapticd::wiring
