// `hapticd peer`'s look at its endpoint before it plays a device there: what the kernel says
// about it (rtnetlink for a CAN interface, sysfs for a GPIO chip and the USB device
// controllers), judged by peer_guard.h, and on CAN a node that already answers at the
// configured id (peer_can_listen.h). Not RT code.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"
#include "service/commands/peer_guard.h"

namespace hapticd::service {

struct PeerEndpointPolicy {
  bool impersonate_on_real_hardware = false;  // --impersonate-on-real-hardware
  double listen_s = 2.0;                      // --listen: CAN, how long to wait for the node
};

// RTM_GETLINK for `interface`: whether it exists, its link type and link kind.
CanLinkFacts read_can_link(const std::string& interface);
// The directory's device: whether it is on the gpio bus, and its parent device's driver.
GpioChipFacts read_gpio_chip(const std::string& chip_dir);
// Every USB device controller under `class_dir` and its driver.
std::vector<UdcFacts> read_udcs(const std::string& class_dir = "/sys/class/udc");

// The whole check, for the configured driver's endpoint. Throws config::ConfigError (exit 2)
// for real hardware without impersonate_on_real_hardware, DeviceError (exit 4) for an
// endpoint the peer cannot use and for a CAN node that already answers; logs the verdict.
void check_peer_endpoint(const config::Config& cfg, const std::string& endpoint,
                         const PeerEndpointPolicy& policy);

}  // namespace hapticd::service
