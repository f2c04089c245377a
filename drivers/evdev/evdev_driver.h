// The evdev driver's half of its registration (drivers/device_entry.h): its section
// device.evdev, the delay it declares from the kernel FF driver's class, the polling interval
// and T, the device on /dev/input/eventN through libevdev, the device over a loopback
// socketpair, `check`'s note and `hapticd devices`.
#pragma once

#include "drivers/device_entry.h"

namespace hapticd::drivers::evdev {

DeviceEntry device_entry();

// The entry's udev_rules: the nodes and settings cfg's device needs, and no other.
void write_udev_rules(const config::Config& cfg, UdevRules& out);

}  // namespace hapticd::drivers::evdev
