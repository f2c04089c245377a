// A driver's half of its registration (docs/devices.md): what the driver knows of itself - its
// name, its config section, the transport delay it declares, its device on real hardware and
// on one end of a loopback socketpair, and what `hapticd check` and `hapticd devices` add. What
// builds a device sees a DriverContext (driver_context.h), never the whole configuration; what
// reads or names configuration keys (the section, the force's sign, udev rules) sees the Config
// its messages locate. The
// simulated device at the other end is sim/'s half (sim/peers/peer_entry.h); the composition
// root, wiring/, joins the two by driver name. A driver never sees its simulated device.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"
#include "config/driver_schema.h"
#include "drivers/device.h"
#include "drivers/driver_context.h"
#include "drivers/io/unique_fd.h"
#include "drivers/udev_rules.h"

namespace hapticd::drivers {

// The one setting of a driver's configuration that reverses the force it commands, as the
// direction check names it when it finds the force reversed (docs/devices.md): the key, its
// value now and the value that reverses the force.
struct ForceReversal {
  std::string key;
  std::string now;
  std::string reversed;
};

struct DeviceEntry {
  std::string_view name;     // the value of device.driver
  std::string_view summary;  // one line, for messages and `hapticd devices`
  // Reads device.<name> (config/driver_schema.h); empty for a driver without a section.
  decltype(config::DriverSchema::read_section) read_section;
  // Not RT-safe, pure. Whole samples between write() and the force acting, from the
  // driver's settings and T: what the gate adds to wall.delay_samples.
  int (*declared_delay)(const DriverContext& ctx) = nullptr;
  // Not RT-safe. The device for real hardware, unconfigured (nothing opened yet); null for a
  // driver that only simulates (sim).
  std::unique_ptr<Device> (*make_device)(const DriverContext& ctx) = nullptr;
  // Not RT-safe. The device on `end`, one end of a SOCK_SEQPACKET socketpair
  // (io::seqpacket_pair) whose other end its simulated device answers on; unconfigured. Null
  // for a driver without a transport (sim).
  std::unique_ptr<Device> (*make_loopback_device)(const DriverContext& ctx,
                                                  io::UniqueFd end) = nullptr;
  // Not RT-safe, pure. Lines `hapticd check` prints after the gate's analysis and lists under
  // "driver_notes" in --json (e.g. the bus load a CAN configuration needs; a line starting
  // "warning:" is one). Null for a driver with nothing to add.
  std::vector<std::string> (*notes)(const DriverContext& ctx) = nullptr;
  // Not RT-safe. What of this driver's kind is attached, each with the configuration keys
  // that select it (`hapticd devices`); null for a driver with nothing to list. A system that
  // cannot be asked is said so in the text, not thrown.
  std::string (*list_devices)() = nullptr;
  // Not RT-safe, pure. The setting that reverses this driver's force for `cfg`. Every driver
  // has one (the conformance suite checks it reverses what the device feels).
  ForceReversal (*force_reversal)(const config::Config& cfg) = nullptr;
  // Not RT-safe, pure. The udev rules `hapticd udev-rules` writes for cfg's device: its
  // nodes granted to the service's group and what must be set as it appears, each explained
  // (drivers/udev_rules.h). Throws config::ConfigError naming the key when the configuration
  // selects the device in a way a rule cannot match exactly. Null for a driver with no device.
  void (*udev_rules)(const config::Config& cfg, UdevRules& out) = nullptr;
};

}  // namespace hapticd::drivers
