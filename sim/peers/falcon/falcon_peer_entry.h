// The simulated Falcon's half of the falcon driver's registration (sim/peers/peer_entry.h): the
// device on the driver's socketpair (falcon_peer.h). No kernel endpoint of its own.
#pragma once

#include "sim/peers/peer_entry.h"

namespace hapticd::sim::falcon {

PeerEntry peer_entry();

}  // namespace hapticd::sim::falcon
