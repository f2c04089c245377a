// The reference Falcon's USB constants both halves of raw_usb_ftdi.cpp use; the raw gadget's
// own plumbing (the transfer block, SIGURG, starting the gadget) is ../raw_gadget.h.
#pragma once

#include <array>
#include <cstdint>

#include "raw_gadget.h"

namespace hapticd::reference::falcon::gadget {

using namespace hapticd::reference::gadget;

constexpr std::uint8_t kConfigValue = 1;
constexpr std::uint16_t kMaxPacket = 64;  // full speed: ep0 and both bulk endpoints
constexpr std::uint8_t kInAddress = 0x81, kOutAddress = 0x02;
constexpr std::array<std::uint8_t, 2> kModemStatus{0x31, 0x60};
// Vendor IN requests a host may make of an FT232 (libftdi's numbers).
constexpr std::uint8_t kGetModemStatus = 5, kGetLatency = 10, kReadEeprom = 0x90;

}  // namespace hapticd::reference::falcon::gadget
