// The GPIO driver's half of its registration (drivers/device_entry.h): device.gpio, the
// declared delay from the PWM period and T, the device on the kernel's lines and sysfs PWM, and
// the device over a loopback socketpair.
#pragma once

#include "drivers/device_entry.h"

namespace hapticd::drivers::gpio {

DeviceEntry device_entry();

// The entry's udev_rules: the nodes and settings cfg's device needs, and no other.
void write_udev_rules(const config::Config& cfg, UdevRules& out);

}  // namespace hapticd::drivers::gpio
