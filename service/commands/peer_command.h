// `hapticd peer`: a driver's simulated device on a kernel endpoint (a USB HID gadget's
// /dev/hidgN, the raw gadget, uhid, a CAN interface, a gpio-sim chip), with the plant of
// device.sim behind it, until a stop signal or --duration. A hapticd run (or any other master)
// on the other side of the kernel interface then drives it as it would hardware. It plays a
// device only where the kernel simulates the hardware (vcan, vxcan, gpio-sim, dummy_hcd,
// uhid) unless told --impersonate-on-real-hardware, and on CAN never at a node id that
// already answers (peer_endpoint.h).
#pragma once

#include <optional>
#include <string>

#include "service/commands/peer_endpoint.h"
#include "service/config_source.h"
#include "service/stop_signals.h"

namespace hapticd::service {

struct PeerOptions {
  ConfigOptions config;
  std::string endpoint;
  std::optional<double> duration_s;
  PeerEndpointPolicy policy;
};

// Exit 0 when stopped, 2 for a bad configuration or real hardware without
// --impersonate-on-real-hardware, 4 when the endpoint cannot be used or a CAN node already
// answers at the configured id, 1 when the peer fails while running.
int peer_command(const PeerOptions& options, SignalWatch& signals);

}  // namespace hapticd::service
