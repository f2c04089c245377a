// Choosing the one attached HID device a configuration means (device.hid.select), and the
// listing `hapticd devices` prints with what a configuration needs to select each device.
// Pure: the enumeration itself is hidapi's (hidapi_transport.h).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivers/hid/hid_settings.h"

namespace hapticd::drivers::hid {

// One entry of hidapi's enumeration (one per top-level collection on some backends).
struct DeviceListing {
  std::string path;
  std::uint16_t vendor_id = 0, product_id = 0, release = 0;
  std::string serial, manufacturer, product;  // hidapi's wide strings, as UTF-8
  int interface = -1;                         // USB interface number; -1 when not USB
  std::uint16_t usage_page = 0, usage = 0;
  std::string bus;  // "usb", "bluetooth", "i2c", "spi", "virtual" or "" (unknown)
};

// hidapi's wide strings (UTF-32 on Linux) as UTF-8; null reads as "".
std::string to_utf8(const wchar_t* text);

// Every listing the selector matches (all its given keys equal; `path` alone when given).
std::vector<DeviceListing> matching(const Selector& s, const std::vector<DeviceListing>& all);

// "vendor_id 0x1209, product_id 0xffb0, serial 'x'": what the selector asks for.
std::string describe(const Selector& s);

// The one listing to open, or a DeviceError-worthy sentence in `error`: none matches (with
// what is attached), or several do (with what tells them apart).
struct Selection {
  std::optional<DeviceListing> device;
  std::string error;
};
Selection select_one(const Selector& s, const std::vector<DeviceListing>& all, const char* backend);

// The `hapticd devices` text for one backend: each device, and the select: mapping that
// picks it out (serial and interface added where the ids alone are ambiguous).
std::string format_listing(const std::vector<DeviceListing>& all, const char* backend);

}  // namespace hapticd::drivers::hid
