// A HID report descriptor written item by item (HID 1.11 6.2.2 short items: the prefix byte's
// tag and type, then the smallest of 1, 2 or 4 data bytes that holds the value), as a firmware
// author writes one by hand. The reference devices' own writer: it shares nothing with the
// driver's DescriptorBuilder.
#pragma once

#include <cstdint>
#include <vector>

namespace hapticd::reference {

class Items {
 public:
  Items& item(std::uint8_t prefix, std::int64_t v) {
    const int size = v >= -128 && v <= 127 ? 1 : v >= -32768 && v <= 32767 ? 2 : 4;
    bytes.push_back(static_cast<std::uint8_t>(prefix | (size == 4 ? 3 : size)));
    for (int i = 0; i < size; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  // An item with exactly these data bytes (a firmware that writes 0x26 0xFF 0x00 for 255).
  Items& raw(std::vector<std::uint8_t> b) {
    bytes.insert(bytes.end(), b.begin(), b.end());
    return *this;
  }
  Items& page(std::int64_t v) { return item(0x04, v); }
  Items& use(std::int64_t v) { return item(0x08, v); }
  Items& logical(std::int64_t lo, std::int64_t hi) { return item(0x14, lo).item(0x24, hi); }
  Items& physical(std::int64_t lo, std::int64_t hi) { return item(0x34, lo).item(0x44, hi); }
  Items& bits(std::int64_t size, std::int64_t count) { return item(0x74, size).item(0x94, count); }
  Items& id(std::int64_t v) { return item(0x84, v); }
  Items& in(std::int64_t flags) { return item(0x80, flags); }
  Items& out(std::int64_t flags) { return item(0x90, flags); }
  Items& feature(std::int64_t flags) { return item(0xB0, flags); }
  Items& open(std::int64_t kind) { return item(0xA0, kind); }
  Items& close() {
    bytes.push_back(0xC0);
    return *this;
  }
  std::vector<std::uint8_t> bytes;
};

// Main item data (HID 1.11 6.2.2.5) and collection kinds (6.2.2.6).
constexpr int kVar = 0x02, kConst = 0x03, kArr = 0x00;
constexpr int kApplication = 1, kLogical = 2, kPhysical = 0;

}  // namespace hapticd::reference
