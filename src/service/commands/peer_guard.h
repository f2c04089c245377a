// What `hapticd peer` may play a device on. A simulated drive on a live CAN bus answers beside
// the real drive at its node id; on a board's own GPIO chip or USB device controller it would
// stand in for hardware a master believes is there. So the peer runs on the kernel's own
// simulations (vcan and vxcan, gpio-sim, dummy_hcd's dummy_udc, uhid) and refuses anything
// else unless told --impersonate-on-real-hardware. These are the decisions, pure functions of
// what the kernel says about an endpoint (peer_endpoint.h reads it), so a test can feed them
// every case, real hardware included. Not RT code.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hapticd::service {

struct EndpointVerdict {
  enum class Kind : std::uint8_t {
    kSimulated,  // a simulation the kernel provides: the peer may run there
    kReal,       // hardware (or what cannot be told from it): only with the flag
    kUnusable,   // not an endpoint of this driver's peer at all: refused, flag or not
  };
  Kind kind = Kind::kUnusable;
  std::string what;  // the facts in words, for the message
};

// A CAN interface as rtnetlink describes it. Every CAN interface, virtual or not, has the
// link type ARPHRD_CAN (280); what tells vcan and vxcan from a controller is the link kind
// (IFLA_INFO_KIND): "vcan", "vxcan"; a controller's driver registers kind "can" (can-dev).
struct CanLinkFacts {
  bool exists = false;
  unsigned type = 0;
  std::string kind;  // empty: the link has none
};
inline constexpr unsigned kArphrdCan = 280;
EndpointVerdict judge_can_link(const std::string& interface, const CanLinkFacts& facts);

// The directory the GPIO peer writes its lines' pull attributes under (the first half of its
// endpoint): a gpio-sim chip's sysfs directory, /sys/devices/platform/gpio-sim.N/gpiochipM.
struct GpioChipFacts {
  bool exists = false;
  bool is_gpio_chip = false;  // a device on the gpio bus (its `subsystem` is /sys/bus/gpio)
  std::string driver;         // the driver of the device the chip belongs to; "" none
};
EndpointVerdict judge_gpio_chip(const std::string& chip_dir, const GpioChipFacts& facts);

// A USB device controller (/sys/class/udc/NAME). A USB gadget made by the HID peer
// (/dev/raw-gadget, or a configfs gadget's /dev/hidgN) appears on one; only dummy_hcd's
// dummy_udc is a simulation, every other controller is a port a real host may be cabled to.
struct UdcFacts {
  std::string name;
  std::string driver;  // its device's driver
};
// uhid (an endpoint ending in "uhid") makes a HID device on this host alone: allowed. A
// gadget endpoint is allowed when every controller the host has is dummy_udc (the raw gadget
// binds to the first it finds; a configfs gadget to the one it was given).
EndpointVerdict judge_hid_endpoint(const std::string& endpoint, const std::vector<UdcFacts>& udcs);

}  // namespace hapticd::service
