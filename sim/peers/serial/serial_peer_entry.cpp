#include "sim/peers/serial/serial_peer_entry.h"

#include "sim/peers/serial/serial_peer.h"

namespace hapticd::sim::serial {

PeerEntry peer_entry() {
  PeerEntry e;
  e.driver = "serial";
  e.make_peer = &make_loopback_peer;
  return e;
}

}  // namespace hapticd::sim::serial
