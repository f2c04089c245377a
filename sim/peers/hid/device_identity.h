// Who the simulated HID device says it is, on whichever link it is made (uhid, a raw USB
// gadget): its USB ids and strings. hapticd selects it by these (device.hid.select).
#pragma once

#include <cstdint>
#include <string>

namespace hapticd::sim::hid {

struct DeviceIdentity {
  std::uint16_t vendor_id = 0x1209, product_id = 0x0001;  // pid.codes' test vendor id
  std::string serial = "hapticd-sim";
  std::string manufacturer = "hapticd";
  std::string name = "hapticd simulated HID device";
};

}  // namespace hapticd::sim::hid
