#include "sim/peers/falcon/falcon_peer_entry.h"

#include "sim/peers/falcon/falcon_peer.h"

namespace hapticd::sim::falcon {

PeerEntry peer_entry() {
  PeerEntry e;
  e.driver = "falcon";
  e.make_peer = &make_loopback_peer;
  return e;
}

}  // namespace hapticd::sim::falcon
