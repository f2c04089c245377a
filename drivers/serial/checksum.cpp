#include "drivers/serial/checksum.h"

#include <array>

namespace hapticd::drivers::serial {
namespace {

// Greg Cook's catalogue (reveng.sourceforge.io/crc-catalogue), the algorithms seen on the
// microcontroller boards people build: SMBus's and Dallas/Maxim 1-Wire's CRC-8, and the
// CCITT (IBM-3740, XMODEM, KERMIT) and IBM (ARC, MODBUS) families of CRC-16.
constexpr std::array<CheckAlgorithm, 9> kAlgorithms{{
    {"sum8", CheckKind::kSum8, {}},
    {"xor8", CheckKind::kXor8, {}},
    {"crc-8/smbus", CheckKind::kCrc, {8, 0x07, 0x00, false, false, 0x00, 0xF4}},
    {"crc-8/maxim-dow", CheckKind::kCrc, {8, 0x31, 0x00, true, true, 0x00, 0xA1}},
    {"crc-16/ibm-3740", CheckKind::kCrc, {16, 0x1021, 0xFFFF, false, false, 0x0000, 0x29B1}},
    {"crc-16/xmodem", CheckKind::kCrc, {16, 0x1021, 0x0000, false, false, 0x0000, 0x31C3}},
    {"crc-16/kermit", CheckKind::kCrc, {16, 0x1021, 0x0000, true, true, 0x0000, 0x2189}},
    {"crc-16/arc", CheckKind::kCrc, {16, 0x8005, 0x0000, true, true, 0x0000, 0xBB3D}},
    {"crc-16/modbus", CheckKind::kCrc, {16, 0x8005, 0xFFFF, true, true, 0x0000, 0x4B37}},
}};

constexpr std::uint16_t reflect(std::uint16_t v, unsigned width) noexcept {
  std::uint16_t r = 0;
  for (unsigned i = 0; i < width; ++i) {
    if ((v >> i) & 1u) r = static_cast<std::uint16_t>(r | (1u << (width - 1 - i)));
  }
  return r;
}

// The Rocksoft model, bit by bit: the definition, which the tables below are built from.
constexpr std::uint16_t crc_bitwise(const CrcParams& p,
                                    std::span<const std::uint8_t> bytes) noexcept {
  const std::uint32_t top = 1u << (p.width - 1);
  const std::uint32_t mask = (top << 1) - 1;
  std::uint32_t reg = p.init;
  for (std::uint8_t b : bytes) {
    const std::uint8_t in = p.refin ? static_cast<std::uint8_t>(reflect(b, 8)) : b;
    reg ^= static_cast<std::uint32_t>(in) << (p.width - 8);
    for (int k = 0; k < 8; ++k) {
      reg = (reg & top) != 0 ? ((reg << 1) ^ p.poly) & mask : (reg << 1) & mask;
    }
  }
  const auto out = static_cast<std::uint16_t>(reg);
  return static_cast<std::uint16_t>((p.refout ? reflect(out, p.width) : out) ^ p.xorout);
}

// A byte at a time (a flooding device makes the scanner check a candidate at every byte): the
// register's step for each byte value. Reflected algorithms (refin and refout, all of the
// catalogue's that reflect) keep the register reflected and shift right.
using Table = std::array<std::uint16_t, 256>;
constexpr Table make_table(const CrcParams& p) {
  Table t{};
  const std::uint32_t mask = (1u << p.width) - 1;
  for (std::uint32_t v = 0; v < 256; ++v) {
    std::uint32_t reg;
    if (p.refin) {
      const std::uint32_t poly = reflect(p.poly, p.width);
      reg = v;
      for (int k = 0; k < 8; ++k) reg = (reg & 1u) != 0 ? (reg >> 1) ^ poly : reg >> 1;
    } else {
      reg = v << (p.width - 8);
      for (int k = 0; k < 8; ++k) {
        reg = (reg & (1u << (p.width - 1))) != 0 ? ((reg << 1) ^ p.poly) & mask : (reg << 1) & mask;
      }
    }
    t[v] = static_cast<std::uint16_t>(reg & mask);
  }
  return t;
}

constexpr std::uint16_t crc_table(const CrcParams& p, const Table& t,
                                  std::span<const std::uint8_t> bytes) noexcept {
  const std::uint32_t mask = (1u << p.width) - 1;
  std::uint32_t reg = p.refin ? reflect(p.init, p.width) : p.init;
  for (std::uint8_t b : bytes) {
    if (p.refin) {
      reg = (reg >> 8) ^ t[(reg ^ b) & 0xFFu];
    } else {
      reg = ((reg << 8) ^ t[((reg >> (p.width - 8)) ^ b) & 0xFFu]) & mask;
    }
  }
  // A reflected register is the reflected CRC already; refout then keeps it so.
  const auto out = static_cast<std::uint16_t>(reg & mask);
  const std::uint16_t value = p.refin == p.refout ? out : reflect(out, p.width);
  return static_cast<std::uint16_t>(value ^ p.xorout);
}

constexpr std::array<Table, kAlgorithms.size()> make_tables() {
  std::array<Table, kAlgorithms.size()> all{};
  for (std::size_t i = 0; i < kAlgorithms.size(); ++i) {
    if (kAlgorithms[i].kind == CheckKind::kCrc) all[i] = make_table(kAlgorithms[i].crc);
  }
  return all;
}
constexpr std::array<Table, kAlgorithms.size()> kTables = make_tables();

// Each catalogue entry reproduces its own check value, bit by bit and a byte at a time alike,
// at compile time.
constexpr bool catalogue_checks() {
  constexpr std::array<std::uint8_t, 9> kDigits{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  for (std::size_t i = 0; i < kAlgorithms.size(); ++i) {
    const CheckAlgorithm& a = kAlgorithms[i];
    if (a.kind != CheckKind::kCrc) continue;
    if (crc_bitwise(a.crc, kDigits) != a.crc.check) return false;
    if (crc_table(a.crc, kTables[i], kDigits) != a.crc.check) return false;
  }
  return true;
}
static_assert(catalogue_checks(), "a CRC of the catalogue does not give its check value");

}  // namespace

std::span<const CheckAlgorithm> check_algorithms() noexcept { return kAlgorithms; }

const CheckAlgorithm* find_check_algorithm(std::string_view name) noexcept {
  for (const CheckAlgorithm& a : kAlgorithms) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

std::uint16_t compute_check(const CheckAlgorithm& a, std::span<const std::uint8_t> bytes) noexcept {
  std::uint8_t acc = 0;
  switch (a.kind) {
    case CheckKind::kSum8:
      for (std::uint8_t b : bytes) acc = static_cast<std::uint8_t>(acc + b);
      return acc;
    case CheckKind::kXor8:
      for (std::uint8_t b : bytes) acc = static_cast<std::uint8_t>(acc ^ b);
      return acc;
    case CheckKind::kCrc: {
      // One of the catalogue's (find_check_algorithm's): its table; anything else bit by bit.
      const std::ptrdiff_t i = &a - kAlgorithms.data();
      if (i >= 0 && i < static_cast<std::ptrdiff_t>(kAlgorithms.size())) {
        return crc_table(a.crc, kTables[static_cast<std::size_t>(i)], bytes);
      }
      return crc_bitwise(a.crc, bytes);
    }
  }
  return 0;
}

}  // namespace hapticd::drivers::serial
