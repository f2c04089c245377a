// The checks a serial frame can carry, as the devices people build use them: an 8-bit sum or
// XOR of the covered bytes, or a CRC of 8 or 16 bits given by its parameters in the Rocksoft
// model (Ross Williams, "A Painless Guide to CRC Error Detection Algorithms", 1993: width,
// poly, init, refin, refout, xorout), with the named algorithms of Greg Cook's "Catalogue of
// parametrised CRC algorithms" a configuration may choose. Pure: no OS header, no allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hapticd::drivers::serial {

struct CrcParams {
  unsigned width = 16;  // 8 or 16
  std::uint16_t poly = 0x1021;
  std::uint16_t init = 0xFFFF;
  bool refin = false;
  bool refout = false;
  std::uint16_t xorout = 0;
  std::uint16_t check = 0;  // the catalogue's CRC of ASCII "123456789"
};

enum class CheckKind : std::uint8_t { kSum8, kXor8, kCrc };

// One algorithm a configuration names (`algorithm: crc-16/ibm-3740`).
struct CheckAlgorithm {
  std::string_view name;
  CheckKind kind = CheckKind::kCrc;
  CrcParams crc;  // kCrc only
  // Bytes the check occupies in the frame.
  std::size_t size() const noexcept { return kind == CheckKind::kCrc ? crc.width / 8 : 1; }
};

// Every algorithm a configuration may name, in the order messages list them.
std::span<const CheckAlgorithm> check_algorithms() noexcept;
const CheckAlgorithm* find_check_algorithm(std::string_view name) noexcept;

// RT-safe: called every tick. The check of `bytes` (a CRC: its final, reflected and xored value).
std::uint16_t compute_check(const CheckAlgorithm& a, std::span<const std::uint8_t> bytes) noexcept;

}  // namespace hapticd::drivers::serial
