#include "wiring/registry.h"

#include <stdexcept>
#include <string>
#include <vector>

#include "config/config_loader.h"
#include "wiring/sim_driver.h"
#if HAPTICD_WITH_HID
#include "drivers/hid/hid_driver.h"
#include "sim/peers/hid/hid_peer_entry.h"
#endif
#if HAPTICD_WITH_CAN
#include "drivers/can/can_driver.h"
#include "sim/peers/can/can_peer_entry.h"
#endif
#if HAPTICD_WITH_GPIO
#include "drivers/gpio/gpio_driver.h"
#include "sim/peers/gpio/gpio_peer_entry.h"
#endif
#if HAPTICD_WITH_EVDEV
#include "drivers/evdev/evdev_driver.h"
#include "sim/peers/evdev/evdev_peer_entry.h"
#endif
#if HAPTICD_WITH_SERIAL
#include "drivers/serial/serial_driver.h"
#include "sim/peers/serial/serial_peer_entry.h"
#endif
#if HAPTICD_WITH_FALCON
#include "drivers/falcon/falcon_driver.h"
#include "sim/peers/falcon/falcon_peer_entry.h"
#endif

namespace hapticd::wiring {
namespace {

// A driver's device and its simulated device, joined by the driver's name (unused in a
// build with only the sim driver, such as the ThreadSanitizer stage's).
[[maybe_unused]] DriverEntry join(const drivers::DeviceEntry& device, const sim::PeerEntry& peer) {
  if (device.name != peer.driver) {
    throw std::logic_error("wiring: the device of driver '" + std::string(device.name) +
                           "' is registered with the peer of '" + std::string(peer.driver) + "'");
  }
  DriverEntry e;
  static_cast<drivers::DeviceEntry&>(e) = device;
  e.peer = peer;
  return e;
}

// One line per driver: the registration.
const std::vector<DriverEntry>& entries() {
  static const std::vector<DriverEntry> kDrivers {
    sim_driver(),
#if HAPTICD_WITH_HID
        join(drivers::hid::device_entry(), sim::hid::peer_entry()),
#endif
#if HAPTICD_WITH_CAN
        join(drivers::can::device_entry(), sim::can_peer_entry()),
#endif
#if HAPTICD_WITH_GPIO
        join(drivers::gpio::device_entry(), sim::gpio::peer_entry()),
#endif
#if HAPTICD_WITH_EVDEV
        join(drivers::evdev::device_entry(), sim::evdev::peer_entry()),
#endif
#if HAPTICD_WITH_SERIAL
        join(drivers::serial::device_entry(), sim::serial::peer_entry()),
#endif
#if HAPTICD_WITH_FALCON
        join(drivers::falcon::device_entry(), sim::falcon::peer_entry()),
#endif
  };
  return kDrivers;
}

}  // namespace

Loopback DriverEntry::make_loopback(const config::Config& cfg) const {
  if (make_in_process != nullptr) return make_in_process(cfg);
  auto [device_end, peer_end] = io::seqpacket_pair();
  Loopback pair;
  try {
    pair.peer = peer.make_peer(cfg, std::move(peer_end));
  } catch (const std::invalid_argument& e) {  // SimAxis: a plant that cannot be simulated
    throw config::ConfigError({cfg.locate("device.sim") + ": device.sim: " + e.what()});
  }
  pair.device = make_loopback_device(cfg, std::move(device_end));
  return pair;
}

std::span<const DriverEntry> registered_drivers() { return entries(); }

const DriverEntry& find_driver(std::string_view name) {
  for (const DriverEntry& d : entries()) {
    if (d.name == name) return d;
  }
  std::string known;
  for (const DriverEntry& d : entries()) known += (known.empty() ? "" : ", ") + std::string(d.name);
  throw DeviceError("device.driver: this build has no driver '" + std::string(name) +
                    "' (it has: " + known + ")");
}

const config::DriverSchemas& driver_schemas() {
  static const config::DriverSchemas schemas = [] {
    config::DriverSchemas s;
    for (const DriverEntry& d : entries()) s.push_back({std::string(d.name), d.read_section});
    return s;
  }();
  return schemas;
}

}  // namespace hapticd::wiring
