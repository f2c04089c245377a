// The driver registry (docs/devices.md): each driver this build has, with its config section, the
// transport delay it declares as a function of that config and the sample period, its factory
// for real hardware, and its loopback pair. `check`, `verify` and `run` all analyse the delay
// declared here, so they analyse the same loop. Adding a driver touches its own folder and
// one line of registry.cpp.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"
#include "config/driver_schema.h"
#include "drivers/device.h"
#include "sim/peers/loopback_peer.h"

namespace hapticd::drivers {

// A driver and the simulated device it talks to (hapticd run --loopback, the conformance
// suite): the driver's own protocol code against its peer over a socketpair.
struct Loopback {
  std::unique_ptr<Device> device;
  std::unique_ptr<sim::LoopbackPeer> peer;  // never null
};

struct DriverEntry {
  std::string_view name;     // the value of device.driver
  std::string_view summary;  // one line, for messages and `hapticd devices`
  // Reads device.<name> (config/driver_schema.h); empty for a driver without a section.
  decltype(config::DriverSchema::read_section) read_section;
  // Not RT-safe, pure. Whole samples between write() and the force acting, from the
  // driver's settings and T: what the gate adds to wall.delay_samples.
  int (*declared_delay)(const config::Config& cfg) = nullptr;
  // Not RT-safe. The device for real hardware, unconfigured (nothing opened yet); null for a
  // driver that only simulates (sim).
  std::unique_ptr<Device> (*make_device)(const config::Config& cfg) = nullptr;
  // Not RT-safe. The device wired to its loopback peer, unconfigured. Throws
  // config::ConfigError for a plant (device.sim) that cannot be simulated.
  Loopback (*make_loopback)(const config::Config& cfg) = nullptr;
  // Not RT-safe. The same peer speaking on a real kernel endpoint instead of a socketpair: a
  // USB HID gadget's /dev/hidgN, a CAN interface, a gpio-sim chip (the format of `endpoint`
  // is the driver's, documented in docs/drivers/<name>.md). `hapticd peer` runs it, so a
  // driver can be tried against a simulated device through the kernel's own interfaces.
  // Null for a driver without one (sim). Throws DeviceError when the endpoint cannot be used.
  std::unique_ptr<sim::LoopbackPeer> (*make_peer_on)(const config::Config& cfg,
                                                     const std::string& endpoint) = nullptr;
  // Not RT-safe, pure. Lines `hapticd check` prints after the gate's analysis and lists under
  // "driver_notes" in --json (e.g. the bus load a CAN configuration needs; a line starting
  // "warning:" is one). Null for a driver with nothing to add.
  std::vector<std::string> (*notes)(const config::Config& cfg) = nullptr;
  // Not RT-safe. What of this driver's kind is attached, each with the configuration keys
  // that select it (`hapticd devices`); null for a driver with nothing to list (sim). A
  // system that cannot be asked is said so in the text, not thrown.
  std::string (*list_devices)() = nullptr;
};

// Every driver of this build, the sim first.
std::span<const DriverEntry> registered_drivers();
// Throws DeviceError naming the drivers there are when `name` is not one of them.
const DriverEntry& find_driver(std::string_view name);
// What the config loader needs to validate device.driver and read the driver's section.
const config::DriverSchemas& driver_schemas();

}  // namespace hapticd::drivers
