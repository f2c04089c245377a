// `hapticd peer`'s look at its endpoint before it plays a device there: the driver's peer
// judges it from what the kernel says (sim/peers/endpoint_verdict.h, the peer entry's
// judge_endpoint), this applies the policy, and the peer makes sure the device it would play
// is not there already (check_endpoint_free: a CAN node answering at the configured id).
// Not RT code.
#pragma once

#include <string>

#include "config/config.h"
#include "sim/peers/peer_entry.h"

namespace hapticd::service {

struct PeerEndpointPolicy {
  bool impersonate_on_real_hardware = false;  // --impersonate-on-real-hardware
  double listen_s = 2.0;                      // --listen: how long to wait for the device
};

// The whole check, for `peer`'s endpoint. Throws config::ConfigError (exit 2) for real
// hardware without impersonate_on_real_hardware, DeviceError (exit 4) for an endpoint the
// peer cannot use and for a device already there; logs the verdict.
void check_peer_endpoint(const sim::PeerEntry& peer, const config::Config& cfg,
                         const std::string& endpoint, const PeerEndpointPolicy& policy);

}  // namespace hapticd::service
