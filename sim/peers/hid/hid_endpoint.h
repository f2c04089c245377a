// Where the HID peer may play (sim/peers/endpoint_verdict.h). /dev/uhid makes a HID device on
// this host alone; a USB gadget (/dev/raw-gadget, or a configfs gadget's /dev/hidgN) appears
// on a USB device controller (/sys/class/udc/NAME), and only dummy_hcd's dummy_udc is a
// simulation: every other controller is a port a real host may be cabled to. Not RT code.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"
#include "sim/peers/endpoint_verdict.h"

namespace hapticd::sim::hid {

struct UdcFacts {
  std::string name;
  std::string driver;  // its device's driver
};

// Every USB device controller under `class_dir` and its driver.
std::vector<UdcFacts> read_udcs(const std::string& class_dir = "/sys/class/udc");
// Pure. uhid (an endpoint ending in "uhid") is allowed; a gadget endpoint when every
// controller the host has is dummy_udc (the raw gadget binds to the first it finds; a configfs
// gadget to the one it was given).
EndpointVerdict judge_hid_endpoint(const std::string& endpoint, const std::vector<UdcFacts>& udcs);
// The peer entry's judge_endpoint.
EndpointVerdict judge_endpoint(const config::Config& cfg, const std::string& endpoint);

// Whether the endpoint's path ends in `tail` ("uhid", "raw-gadget"): which transport it is.
bool endpoint_is(const std::string& endpoint, const std::string& tail);

}  // namespace hapticd::sim::hid
