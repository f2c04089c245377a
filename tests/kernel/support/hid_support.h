// HID helpers shared by UsbHidGadget and UhidDevice: a vendor-defined report descriptor for
// tests, and finding the hidraw node the kernel made for a device.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace hapticd::kernel_test {

// One input and one output report on the vendor page 0xFF00, each a numbered report of
// byte-sized fields (so hid_read returns and hid_write takes the report id as byte 0).
struct VendorReports {
  std::uint8_t input_id = 1;
  std::uint8_t input_bytes = 8;  // payload, without the report id
  std::uint8_t output_id = 2;
  std::uint8_t output_bytes = 8;  // payload, without the report id
};
std::vector<std::uint8_t> vendor_report_descriptor(const VendorReports& reports);

// The /dev/hidrawN of the HID device with this bus type (BUS_USB, BUS_VIRTUAL, ...), vendor,
// product and serial (HID_UNIQ: the USB iSerialNumber or uhid's uniq), if the kernel made one.
std::optional<std::string> find_hidraw(std::uint16_t bus, std::uint16_t vendor_id,
                                       std::uint16_t product_id, const std::string& serial);
// Whether the kernel lists that node now (one that vanishes while it is being looked at is not).
bool hidraw_listed(std::uint16_t bus, std::uint16_t vendor_id, std::uint16_t product_id,
                   const std::string& serial);
// Whether that device's HID driver is bound: its probe is over. The hidraw node appears in the
// middle of it (hid_connect), before the kernel's own PID host (hid-pidff, the ff_init called
// last) may reset the device and try an effect: a host that meets the device before the probe
// returns races that.
bool hid_bound(std::uint16_t bus, std::uint16_t vendor_id, std::uint16_t product_id,
               const std::string& serial);

}  // namespace hapticd::kernel_test
