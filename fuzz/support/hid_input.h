// How the hid_codec fuzz target reads the rest of its input (after byte 0, which picks the
// mode): front to back, little-endian, and past its end every read is 0, so any input is a
// whole case. The corpus and regression inputs under fuzz/*/hid_codec are written in this
// encoding: change a read here and they describe other cases.
#pragma once

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <limits>
#include <optional>
#include <span>

#include "drivers/field/field.h"
#include "drivers/hid/report_layout.h"

namespace hapticd::fuzz {

class HidInput {
 public:
  explicit HidInput(std::span<const std::uint8_t> b) : b_(b) {}
  std::uint8_t u8() { return at_ < b_.size() ? b_[at_++] : 0; }
  // Separate statements: the operands of | are unsequenced.
  std::uint16_t u16() {
    const unsigned lo = u8();
    return static_cast<std::uint16_t>(lo | unsigned{u8()} << 8);
  }
  std::uint32_t u32() {
    const std::uint32_t lo = u16();
    return lo | std::uint32_t{u16()} << 16;
  }
  // A value from the table (the edges the codecs clamp, round or refuse), or any double.
  double number() {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    constexpr double kTiny = std::numeric_limits<double>::denorm_min();
    constexpr double kFloatMax = static_cast<double>(FLT_MAX);
    static constexpr double kNumbers[] = {
        0.0,    1.0,    -1.0,  0.5,     1.5,       2.5,     10.0,    1e-3, -1e-3,        1e-5,
        127.0,  127.5,  255.0, 1e4,     10000.5,   32767.0, 65535.0, 1e9,  4294967295.0, 1e300,
        -1e300, 1e-300, kTiny, DBL_MAX, kFloatMax, 0.1,     -0.0,    kNaN, kInf,         -kInf};
    const std::uint8_t s = u8();
    if (s < 0xF0) return kNumbers[s % std::size(kNumbers)];
    const std::uint64_t lo = u32();
    return std::bit_cast<double>(lo | std::uint64_t{u32()} << 32);
  }
  // Type byte: bits 0-2 the type (mod 7: u8, i8, u16, i16, u32, i32, f32), 3 big-endian, 4 a
  // 16-bit offset, 5 a scale, 6 an offset in SI units, 7 a field of any width at any bit:
  // after the offset, a shape byte (bits 0-2 the bit, 3 signed, 4 wraps: read by the layout
  // for its position) and a width byte (1 + its value mod 40: past 32 too, which validate
  // refuses). Inputs written before bit 7 meant anything read the same.
  drivers::hid::FieldSpec field() {
    namespace hid = drivers::hid;
    const std::uint8_t t = u8();
    hid::FieldSpec f = hid::typed(static_cast<hid::FieldType>((t & 7u) % 7u));
    f.endian = (t & 8u) != 0 ? hid::Endian::kBig : hid::Endian::kLittle;
    f.byte = (t & 16u) != 0 ? u16() : u8();
    last_wraps_ = false;
    if ((t & 128u) != 0) {
      const std::uint8_t shape = u8();
      f.bit = shape & 7u;
      f.is_signed = (shape & 8u) != 0;
      f.is_float = false;
      last_wraps_ = (shape & 16u) != 0;
      f.bits = 1u + u8() % 40u;
    }
    if ((t & 32u) != 0) f.scale = number();
    if ((t & 64u) != 0) f.offset = number();
    return f;
  }
  // Whether the last field() read had its wraps bit.
  bool last_wraps() const { return last_wraps_; }
  // 0xFF: a 16-bit length follows (past kMaxReportData, which validate refuses).
  std::size_t length() {
    const std::uint8_t n = u8();
    return n == 0xFF ? u16() : n;
  }
  std::optional<drivers::hid::FeatureLayout> feature(bool present) {
    if (!present) return std::nullopt;
    // Braces evaluate left to right: id, length, field, on, off.
    return drivers::hid::FeatureLayout{u8(), length(), field(), number(), number()};
  }
  // What is left, unread.
  std::span<const std::uint8_t> rest() const { return b_.subspan(std::min(at_, b_.size())); }

 private:
  std::span<const std::uint8_t> b_;
  std::size_t at_ = 0;
  bool last_wraps_ = false;
};

}  // namespace hapticd::fuzz
