// The serial driver's half of its registration (drivers/device_entry.h): device.serial, the
// declared delay from the port's latency and T, the device on a tty and over a loopback
// socketpair, the ports `hapticd devices` lists and the udev rules of the configured one.
#pragma once

#include "drivers/device_entry.h"

namespace hapticd::drivers::serial {

DeviceEntry device_entry();

// The entry's udev_rules: the configured port granted to the group and, on an FTDI adapter,
// its latency timer set to device.serial.latency_ms as it appears.
void write_udev_rules(const config::Config& cfg, UdevRules& out);
// The entry's list_devices: the USB serial ports attached, each with its device.serial.port.
std::string list_ports();

}  // namespace hapticd::drivers::serial
