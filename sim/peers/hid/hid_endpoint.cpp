#include "sim/peers/hid/hid_endpoint.h"

#include <filesystem>

namespace hapticd::sim::hid {

using Kind = EndpointVerdict::Kind;

bool endpoint_is(const std::string& endpoint, const std::string& tail) {
  return endpoint.size() >= tail.size() &&
         endpoint.compare(endpoint.size() - tail.size(), tail.size(), tail) == 0;
}

std::vector<UdcFacts> read_udcs(const std::string& class_dir) {
  std::vector<UdcFacts> udcs;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(class_dir, ec)) {
    udcs.push_back({e.path().filename().string(), sysfs_driver_of(e.path() / "device")});
  }
  return udcs;
}

EndpointVerdict judge_hid_endpoint(const std::string& endpoint, const std::vector<UdcFacts>& udcs) {
  if (endpoint_is(endpoint, "uhid")) {
    return {Kind::kSimulated, endpoint + " makes a HID device on this host only (no USB port)"};
  }
  if (udcs.empty()) {
    return {Kind::kUnusable,
            "a USB gadget needs a USB device controller and /sys/class/udc has none (load "
            "dummy_hcd for a simulated one)"};
  }
  std::string real;
  for (const UdcFacts& u : udcs) {
    if (u.driver == "dummy_udc") continue;
    real += (real.empty() ? "" : ", ") + u.name + " (driver '" + u.driver + "')";
  }
  if (real.empty()) {
    return {Kind::kSimulated, "every USB device controller here is dummy_hcd's dummy_udc"};
  }
  return {Kind::kReal, "this host has a real USB device controller, " + real +
                           ", that a USB gadget of " + endpoint + " may appear on"};
}

EndpointVerdict judge_endpoint(const config::Config&, const std::string& endpoint) {
  return judge_hid_endpoint(endpoint, read_udcs());
}

}  // namespace hapticd::sim::hid
