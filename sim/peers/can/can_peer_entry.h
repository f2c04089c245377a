// The simulated drives' half of the CAN driver's registration (sim/peers/peer_entry.h): the
// CiA 402 drive or the ODrive axis of device.can's profile, on the driver's socketpair or on a
// real interface (`hapticd peer --endpoint vcan0`).
#pragma once

#include <memory>

#include "drivers/can/can_socket.h"
#include "sim/peers/peer_entry.h"

namespace hapticd::sim {

PeerEntry can_peer_entry();

// The simulated drive of cfg's profile on `socket` (the tests build their own rigs with it).
// `realtime`: its heartbeats and watchdogs keep wall-clock time (a peer on a real interface)
// rather than counting the protocol's own trigger. Throws config::ConfigError for a plant
// (device.sim) that cannot be simulated.
std::unique_ptr<LoopbackPeer> make_can_peer(const config::Config& cfg,
                                            drivers::can::CanSocket socket, bool realtime);

}  // namespace hapticd::sim
