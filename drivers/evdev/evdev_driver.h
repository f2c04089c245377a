// The evdev driver's half of its registration (drivers/device_entry.h): its section
// device.evdev, the delay it declares from the kernel FF driver's class, the polling interval
// and T, the device on /dev/input/eventN through libevdev, the device over a loopback
// socketpair, `check`'s note and `hapticd devices`.
#pragma once

#include "drivers/device_entry.h"

namespace hapticd::drivers::evdev {

DeviceEntry device_entry();

}  // namespace hapticd::drivers::evdev
