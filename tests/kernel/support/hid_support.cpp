#include "hid_support.h"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "sysfs.h"

namespace hapticd::kernel_test {

std::vector<std::uint8_t> vendor_report_descriptor(const VendorReports& r) {
  // clang-format off
  return {
      0x06, 0x00, 0xFF,        // Usage Page (Vendor 0xFF00)
      0x09, 0x01,              // Usage (1)
      0xA1, 0x01,              // Collection (Application)
      0x15, 0x00,              //   Logical Minimum (0)
      0x26, 0xFF, 0x00,        //   Logical Maximum (255)
      0x75, 0x08,              //   Report Size (8 bits)
      0x85, r.input_id,        //   Report ID
      0x09, 0x02,              //   Usage (2)
      0x95, r.input_bytes,     //   Report Count
      0x81, 0x02,              //   Input (Data, Variable, Absolute)
      0x85, r.output_id,       //   Report ID
      0x09, 0x03,              //   Usage (3)
      0x95, r.output_bytes,    //   Report Count
      0x91, 0x02,              //   Output (Data, Variable, Absolute)
      0xC0,                    // End Collection
  };
  // clang-format on
}

std::optional<std::string> find_hidraw(std::uint16_t bus, std::uint16_t vendor_id,
                                       std::uint16_t product_id, const std::string& serial) {
  char id[32];
  std::snprintf(id, sizeof id, "HID_ID=%04X:%08X:%08X", bus, vendor_id, product_id);
  const std::string uniq = "HID_UNIQ=" + serial;
  for (const auto& node : list_dir("/sys/class/hidraw")) {
    // The hidraw node's parent is the HID device, whose uevent names bus, ids and serial.
    std::istringstream uevent(read_text("/sys/class/hidraw/" + node + "/device/uevent"));
    bool id_matches = false, uniq_matches = false;
    for (std::string line; std::getline(uevent, line);) {
      id_matches = id_matches || line == id;
      uniq_matches = uniq_matches || line == uniq;
    }
    if (id_matches && uniq_matches) return "/dev/" + node;
  }
  return std::nullopt;
}

bool hidraw_listed(std::uint16_t bus, std::uint16_t vendor_id, std::uint16_t product_id,
                   const std::string& serial) {
  try {
    return find_hidraw(bus, vendor_id, product_id, serial).has_value();
  } catch (const std::exception&) {
    return false;
  }
}

bool hid_bound(std::uint16_t bus, std::uint16_t vendor_id, std::uint16_t product_id,
               const std::string& serial) {
  try {
    const auto node = find_hidraw(bus, vendor_id, product_id, serial);
    if (!node) return false;
    const std::string name = std::filesystem::path(*node).filename();
    return std::filesystem::exists("/sys/class/hidraw/" + name + "/device/driver");
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace hapticd::kernel_test
