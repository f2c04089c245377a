// The HID driver's half of its registration (drivers/device_entry.h): its section device.hid,
// the delay it declares from the polling interval and T, the device over hidapi, the device
// over a loopback socketpair, and `hapticd devices`.
#pragma once

#include "drivers/device_entry.h"

namespace hapticd::drivers::hid {

DeviceEntry device_entry();

}  // namespace hapticd::drivers::hid
