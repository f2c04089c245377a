// Numbers shown in hexadecimal, one way for every layer: "0x", then at least `digits` digits.
// Upper case is how CANopen objects, CAN ids and HID usages are written (0x6041, 0x701,
// 0x01:0x30); lower case how USB ids are (lsusb, sysfs and udev: 1209:ffb0).
#pragma once

#include <cstdint>
#include <string>

namespace hapticd::base {

enum class HexCase : std::uint8_t { kUpper, kLower };

// Not RT-safe (allocates). "0x" and `value` zero-padded to `digits` digits, never cut short:
// hex(0x701, 3) is "0x701", hex(0xFF, 8) "0x000000FF", hex(0xffb0, 4, HexCase::kLower)
// "0xffb0"; substr(2) of it is the bare digits a udev rule matches.
std::string hex(std::uint64_t value, int digits = 1, HexCase letters = HexCase::kUpper);

}  // namespace hapticd::base
