// The simulated serial device's half of the serial driver's registration
// (sim/peers/peer_entry.h): a board speaking the configured frames on the driver's socketpair
// (serial_peer.h).
#pragma once

#include "sim/peers/peer_entry.h"

namespace hapticd::sim::serial {

PeerEntry peer_entry();

}  // namespace hapticd::sim::serial
