// CRCs by the parametrised model of Ross Williams, "A Painless Guide to CRC Error Detection
// Algorithms" (1993), section 15 ("A Parameterized Model For CRC Algorithms": WIDTH, POLY,
// INIT, REFIN, REFOUT, XOROUT, CHECK), computed bit by bit with no table, as section 17's model
// implementation (cm_nxt) does: each message bit meets the register's top bit directly, no zero
// augmentation, the form in which the model's INIT is defined. The parameters are Greg Cook's
// "Catalogue of parametrised CRC algorithms" entries. The stream reference device frames with
// CRC-16/IBM-3740 (alias CRC-16/CCITT-FALSE, CRC-16/AUTOSAR): width 16, poly 0x1021, init 0xFFFF,
// refin false, refout false, xorout 0x0000, check 0x29B1. Each model is checked against its
// catalogue CHECK (the CRC of ASCII "123456789") at compile time, the reflected ones too, so the
// model's reflection paths are proven as well as the one the device uses.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace hapticd::reference {

struct CrcModel {
  int width;           // bits, 1..32
  std::uint32_t poly;  // without its top bit, unreflected
  std::uint32_t init;  // register before the first bit, unreflected
  bool refin;          // each input byte's bit 0 goes in first
  bool refout;         // the register is reflected before xorout
  std::uint32_t xorout;
  std::uint32_t check;  // the catalogue's CRC of "123456789"
};

inline constexpr CrcModel kCrc16Ibm3740{16, 0x1021, 0xFFFF, false, false, 0x0000, 0x29B1};
inline constexpr CrcModel kCrc16Arc{16, 0x8005, 0x0000, true, true, 0x0000, 0xBB3D};
inline constexpr CrcModel kCrc32IsoHdlc{32,   0x04C11DB7, 0xFFFFFFFF, true,
                                        true, 0xFFFFFFFF, 0xCBF43926};

constexpr std::uint32_t crc_reflect(std::uint32_t v, int bits) {
  std::uint32_t r = 0;
  for (int i = 0; i < bits; ++i) r |= ((v >> i) & 1u) << (bits - 1 - i);
  return r;
}

// The register after `bytes`, from `reg` (start with model.init), before refout and xorout.
template <typename Bytes>
constexpr std::uint32_t crc_feed(const CrcModel& m, std::uint32_t reg, const Bytes& bytes) {
  const std::uint32_t top = 1u << (m.width - 1);
  const std::uint32_t mask = m.width == 32 ? 0xFFFFFFFFu : (1u << m.width) - 1u;
  for (const auto c : bytes) {
    std::uint32_t byte = static_cast<std::uint8_t>(c);
    if (m.refin) byte = crc_reflect(byte, 8);
    for (int i = 7; i >= 0; --i) {  // the byte's bits, most significant first
      const bool feedback = ((reg & top) != 0) != (((byte >> i) & 1u) != 0);
      reg = (reg << 1) & mask;
      if (feedback) reg ^= m.poly;
    }
  }
  return reg;
}

template <typename Bytes>
constexpr std::uint32_t crc_of(const CrcModel& m, const Bytes& bytes) {
  std::uint32_t reg = crc_feed(m, m.init, bytes);
  if (m.refout) reg = crc_reflect(reg, m.width);
  return reg ^ m.xorout;
}

constexpr bool crc_model_checks(const CrcModel& m) {
  return crc_of(m, std::string_view("123456789")) == m.check;
}

static_assert(crc_model_checks(kCrc16Ibm3740), "CRC-16/IBM-3740 check value 0x29B1");
static_assert(crc_model_checks(kCrc16Arc), "CRC-16/ARC check value 0xBB3D");
static_assert(crc_model_checks(kCrc32IsoHdlc), "CRC-32/ISO-HDLC check value 0xCBF43926");

// CRC-16/IBM-3740 of `bytes`: what the stream device puts in its frames and checks in the host's.
std::uint16_t crc16_ibm3740(std::span<const std::uint8_t> bytes);

}  // namespace hapticd::reference
