// Where the CAN peer may play (sim/peers/endpoint_verdict.h): a virtual bus, vcan or vxcan,
// as rtnetlink describes the interface. Every CAN interface, virtual or not, has the link type
// ARPHRD_CAN (280); what tells vcan and vxcan from a controller is the link kind
// (IFLA_INFO_KIND): "vcan", "vxcan"; a controller's driver registers kind "can" (can-dev).
// Not RT code.
#pragma once

#include <string>

#include "config/config.h"
#include "sim/peers/endpoint_verdict.h"

namespace hapticd::sim {

struct CanLinkFacts {
  bool exists = false;
  unsigned type = 0;
  std::string kind;  // empty: the link has none
};
inline constexpr unsigned kArphrdCan = 280;

// RTM_GETLINK for `interface`: whether it exists, its link type and link kind. Throws
// DeviceError when the kernel cannot be asked.
CanLinkFacts read_can_link(const std::string& interface);
// Pure.
EndpointVerdict judge_can_link(const std::string& interface, const CanLinkFacts& facts);
// The peer entry's judge_endpoint: the endpoint is the interface.
EndpointVerdict judge_can_endpoint(const config::Config& cfg, const std::string& interface);

}  // namespace hapticd::sim
