// The Falcon driver's half of its registration (drivers/device_entry.h): device.falcon, the
// declared delay, the device over libusb and over a loopback socketpair, the Falcons `hapticd
// devices` lists and the udev rule of the configured one.
#pragma once

#include "drivers/device_entry.h"

namespace hapticd::drivers::falcon {

DeviceEntry device_entry();

// The entry's udev_rules: the Falcon's USB device node (0403:cb48, its serial when configured)
// granted to the group.
void write_udev_rules(const config::Config& cfg, UdevRules& out);

}  // namespace hapticd::drivers::falcon
