// The CAN driver's half of its registration (drivers/device_entry.h; docs/drivers/can.md):
// device.can, the delay each profile declares, the CiA 402 and ODrive devices on a SocketCAN
// interface or over a loopback socketpair, and the bus load `hapticd check` reports.
#pragma once

#include <functional>
#include <memory>

#include "drivers/can/can_socket.h"
#include "drivers/device_entry.h"

namespace hapticd::drivers::can {

DeviceEntry device_entry();

// The entry's udev_rules: the nodes and settings cfg's device needs, and no other.
void write_udev_rules(const config::Config& cfg, UdevRules& out);

// The device of ctx's profile, opening its transport with `open` at configure (the tests
// build their own rigs with it).
std::unique_ptr<Device> make_can_device(const DriverContext& ctx, std::function<CanSocket()> open);

}  // namespace hapticd::drivers::can
