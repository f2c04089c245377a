#include "drivers/registry.h"

#include <array>
#include <string>

#include "drivers/sim/sim_driver.h"
#if HAPTICD_WITH_HID
#include "drivers/hid/hid_driver.h"
#endif
#if HAPTICD_WITH_CAN
#include "drivers/can/can_driver.h"
#endif
#if HAPTICD_WITH_GPIO
#include "drivers/gpio/gpio_driver.h"
#endif

namespace hapticd::drivers {
namespace {

// One line per driver: the registration.
const std::array kDrivers {
  sim_driver::sim_driver(),
#if HAPTICD_WITH_HID
      hid::hid_driver(),
#endif
#if HAPTICD_WITH_CAN
      can::can_driver(),
#endif
#if HAPTICD_WITH_GPIO
      gpio::gpio_driver(),
#endif
};

}  // namespace

std::span<const DriverEntry> registered_drivers() { return kDrivers; }

const DriverEntry& find_driver(std::string_view name) {
  for (const DriverEntry& d : kDrivers) {
    if (d.name == name) return d;
  }
  std::string known;
  for (const DriverEntry& d : kDrivers) known += (known.empty() ? "" : ", ") + std::string(d.name);
  throw DeviceError("device.driver: this build has no driver '" + std::string(name) +
                    "' (it has: " + known + ")");
}

const config::DriverSchemas& driver_schemas() {
  static const config::DriverSchemas schemas = [] {
    config::DriverSchemas s;
    for (const DriverEntry& d : kDrivers) s.push_back({std::string(d.name), d.read_section});
    return s;
  }();
  return schemas;
}

}  // namespace hapticd::drivers
