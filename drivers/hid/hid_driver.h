// The HID driver's entry in the registry (drivers/registry.h): its section device.hid, the
// delay it declares from the polling interval and T, the device over hidapi, the loopback pair
// over a socketpair, the same simulated device on a USB HID gadget (`hapticd peer --endpoint
// /dev/hidgN`), and `hapticd devices`.
#pragma once

#include "drivers/registry.h"

namespace hapticd::drivers::hid {

DriverEntry hid_driver();

}  // namespace hapticd::drivers::hid
