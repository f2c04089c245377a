// The simulated drives' half of the CAN driver's registration (sim/peers/peer_entry.h): the
// CiA 402 drive or the ODrive axis of device.can's profile, on the driver's socketpair or on a
// real interface (`hapticd peer --endpoint vcan0`).
#pragma once

#include <memory>

#include "drivers/can/can_socket.h"
#include "sim/peers/can/can_peer_base.h"
#include "sim/peers/peer_entry.h"

namespace hapticd::sim {

PeerEntry can_peer_entry();

// The simulated device of cfg on `socket` (the tests build their own rigs with it): the drive
// of cfg's profile at its one node, or a bus of one drive per node moving one mechanism
// (can_bus_peer.h). `realtime`: its heartbeats and watchdogs keep wall-clock time (a peer on
// a real interface) rather than counting the protocol's own trigger. Throws
// config::ConfigError for a plant (device.sim) that cannot be simulated.
std::unique_ptr<LoopbackPeer> make_can_peer(const config::Config& cfg,
                                            drivers::can::CanSocket socket, bool realtime);
// The drive of cfg's profile at its first node, moving `joint` (none: an axis of its own).
// Throws std::invalid_argument for a plant that cannot be simulated.
std::unique_ptr<CanPeerBase> make_can_drive(const config::Config& cfg,
                                            drivers::can::CanSocket socket, bool realtime,
                                            const SharedJoint& joint);

}  // namespace hapticd::sim
