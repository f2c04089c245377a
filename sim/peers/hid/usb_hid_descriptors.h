// The USB descriptors of the simulated HID device when it is a USB device of its own (the raw
// gadget peer, raw_gadget_peer.h): one configuration, one HID interface with an interrupt IN
// and an interrupt OUT endpoint, full speed, polled every 1 ms (bInterval 1, as open
// firmwares declare). Pure: no OS headers beyond the USB chapter 9 constants spelled out here.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/peers/hid/device_identity.h"

namespace hapticd::sim::hid {

struct UsbHidDescriptors {
  static constexpr std::uint8_t kInEndpoint = 0x81;   // EP1 IN, interrupt
  static constexpr std::uint8_t kOutEndpoint = 0x02;  // EP2 OUT, interrupt
  static constexpr std::uint16_t kMaxPacket = 64;     // full speed's interrupt maximum
  static constexpr std::uint8_t kConfiguration = 1;

  std::vector<std::uint8_t> device;         // 18 bytes
  std::vector<std::uint8_t> configuration;  // configuration, interface, HID, two endpoints
  std::vector<std::uint8_t> hid;            // the HID class descriptor alone
  std::vector<std::uint8_t> report;         // the report descriptor, as the firmware has it
  std::vector<std::uint8_t> in_endpoint, out_endpoint;  // 7 bytes each, for enabling them
  DeviceIdentity identity;

  // String descriptor `index` (0: the language list; 1 manufacturer, 2 product, 3 serial),
  // UTF-16LE from the identity's ASCII; nothing for an index the device does not have.
  std::optional<std::vector<std::uint8_t>> string(std::uint8_t index) const;
};

// Throws std::invalid_argument for a report descriptor over 65535 bytes or a string over 126
// characters (what a descriptor's length fields can say).
UsbHidDescriptors make_usb_hid_descriptors(const DeviceIdentity& identity,
                                           std::vector<std::uint8_t> report_descriptor);

}  // namespace hapticd::sim::hid
