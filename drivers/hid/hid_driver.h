// The HID driver's half of its registration (drivers/device_entry.h): its section device.hid,
// the delay it declares from the polling interval and T, the device over hidapi, the device
// over a loopback socketpair, and `hapticd devices`.
#pragma once

#include "drivers/device_entry.h"

namespace hapticd::drivers::hid {

DeviceEntry device_entry();

// The entry's udev_rules: the nodes and settings cfg's device needs, and no other.
void write_udev_rules(const config::Config& cfg, UdevRules& out);

}  // namespace hapticd::drivers::hid
