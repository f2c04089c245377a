#include "crc.h"

namespace hapticd::reference {

std::uint16_t crc16_ibm3740(std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint16_t>(crc_of(kCrc16Ibm3740, bytes));
}

}  // namespace hapticd::reference
