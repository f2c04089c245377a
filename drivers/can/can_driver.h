// The CAN driver's entry in the registry (docs/drivers/can.md): device.can, the delay each profile
// declares, the CiA 402 and ODrive devices on a SocketCAN interface or over a socketpair with
// their simulated drive, the simulated drive on a real interface (`hapticd peer --endpoint
// vcan0`), and the bus load `hapticd check` reports.
#pragma once

#include <memory>
#include <string>

#include "drivers/can/can_socket.h"
#include "drivers/registry.h"

namespace hapticd::drivers::can {

DriverEntry can_driver();

// The simulated device of cfg's profile on `socket` (the tests build their own rigs with it).
std::unique_ptr<sim::LoopbackPeer> make_can_peer(const config::Config& cfg, CanSocket socket,
                                                 bool realtime);
// The device of cfg's profile, opening its transport with `open` at configure.
std::unique_ptr<Device> make_can_device(const config::Config& cfg, std::function<CanSocket()> open);
// The receive filters of cfg's profile: the frames the driver (or, with `peer`, the
// simulated device) needs to see.
std::vector<IdFilter> receive_filters(const config::Config& cfg, bool peer);

}  // namespace hapticd::drivers::can
