#include "service/commands/peer_guard.h"

namespace hapticd::service {
namespace {

using Kind = EndpointVerdict::Kind;

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

EndpointVerdict judge_can_link(const std::string& interface, const CanLinkFacts& facts) {
  if (!facts.exists) return {Kind::kUnusable, "there is no network interface '" + interface + "'"};
  if (facts.type != kArphrdCan) {
    return {Kind::kUnusable, interface + " is not a CAN interface (link type " +
                                 std::to_string(facts.type) + ", CAN's is 280)"};
  }
  if (facts.kind == "vcan" || facts.kind == "vxcan") {
    return {Kind::kSimulated, interface + " is a virtual CAN bus (" + facts.kind + ")"};
  }
  if (facts.kind.empty()) {
    return {Kind::kReal, interface + " is a CAN interface of no link kind, not vcan or vxcan"};
  }
  return {Kind::kReal, interface + " is a CAN interface of link kind '" + facts.kind +
                           "' (a controller's), not vcan or vxcan"};
}

EndpointVerdict judge_gpio_chip(const std::string& chip_dir, const GpioChipFacts& facts) {
  if (!facts.exists) return {Kind::kUnusable, "there is no directory " + chip_dir};
  if (!facts.is_gpio_chip) {
    return {Kind::kUnusable, chip_dir +
                                 " is not a GPIO chip's sysfs directory (a gpio-sim chip's is "
                                 "/sys/devices/platform/gpio-sim.N/gpiochipM)"};
  }
  if (facts.driver == "gpio-sim") return {Kind::kSimulated, chip_dir + " is a gpio-sim chip"};
  return {Kind::kReal,
          chip_dir + " is a GPIO chip of " +
              (facts.driver.empty() ? std::string("no driver") : "driver '" + facts.driver + "'") +
              ", not gpio-sim"};
}

EndpointVerdict judge_hid_endpoint(const std::string& endpoint, const std::vector<UdcFacts>& udcs) {
  if (ends_with(endpoint, "uhid")) {
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

}  // namespace hapticd::service
