// `hapticd peer`: a driver's simulated device on a real kernel endpoint (a USB HID gadget's
// /dev/hidgN, a CAN interface, a gpio-sim chip), with the plant of device.sim behind it, until
// a stop signal or --duration. A hapticd run (or any other master) on the other side of the
// kernel interface then drives it as it would hardware.
#pragma once

#include <optional>
#include <string>

#include "service/config_source.h"
#include "service/stop_signals.h"

namespace hapticd::service {

struct PeerOptions {
  ConfigOptions config;
  std::string endpoint;
  std::optional<double> duration_s;
};

// Exit 0 when stopped, 2 for a bad configuration, 4 when the endpoint cannot be used, 1 when
// the peer fails while running.
int peer_command(const PeerOptions& options, SignalWatch& signals);

}  // namespace hapticd::service
