// A simulated device's half of its driver's registration (docs/devices.md): the peer that
// answers a driver on the other end of its loopback socketpair, and the same peer on a real
// kernel endpoint. The driver's half is drivers/device_entry.h; the composition root, wiring/,
// joins the two by driver name. For a peer library (sim/peers/<name>/), which links the fd
// helpers (drivers/io/).
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "config/config.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/endpoint_verdict.h"
#include "sim/peers/loopback_peer.h"

namespace hapticd::sim {

struct PeerEntry {
  std::string_view driver;  // the value of device.driver this peer answers for
  // Not RT-safe. The simulated device of cfg on `end`, one end of a SOCK_SEQPACKET socketpair
  // whose other end the driver's device holds. Throws config::ConfigError for a configuration
  // the peer cannot simulate, std::invalid_argument for a plant (device.sim) that cannot be.
  std::unique_ptr<LoopbackPeer> (*make_peer)(const config::Config& cfg, io::UniqueFd end) = nullptr;
  // Not RT-safe. The same simulated device on a real kernel endpoint instead of a socketpair:
  // a USB HID gadget's /dev/hidgN, a CAN interface, a gpio-sim chip (the format of `endpoint`
  // is the driver's, documented in docs/drivers/<name>.md). `hapticd peer` runs it, so a
  // driver can be tried against a simulated device through the kernel's own interfaces. Null
  // for a peer without one. Throws DeviceError when the endpoint cannot be used.
  std::unique_ptr<LoopbackPeer> (*make_peer_on)(const config::Config& cfg,
                                                const std::string& endpoint) = nullptr;
  // Not RT-safe. Whether `endpoint` is a simulation the kernel provides, real hardware, or no
  // endpoint of this peer at all, from what the kernel says about it (endpoint_verdict.h).
  // Throws DeviceError when the kernel cannot be asked. Null: no judgement (real, to be safe).
  EndpointVerdict (*judge_endpoint)(const config::Config& cfg,
                                    const std::string& endpoint) = nullptr;
  // Not RT-safe. On an endpoint the peer may use: refuses (DeviceError) when the device the
  // peer would play is already there and answers within `listen_s` (a CAN node at its id).
  // Null for a peer whose endpoint cannot hold a second device.
  void (*check_endpoint_free)(const config::Config& cfg, const std::string& endpoint,
                              double listen_s) = nullptr;
};

}  // namespace hapticd::sim
