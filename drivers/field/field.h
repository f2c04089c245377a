// One numeric field of a message a device sends or takes (a HID vendor report's data, a
// serial frame), as its layout puts it: where it starts in the message (a byte offset, and a
// bit within it), its width (1..32 bits), signed or not, a float, its byte order, and the
// affine map to SI units (SI = raw * scale + offset). Fields need not be byte-aligned: the
// Nintendo Switch Pro Controller packs its sticks' 12-bit axes three bytes to two
// (X = b5 | (b6 & 0x0f) << 8). Pure code: no OS headers, no allocation after construction, so
// the drivers, their loopback peers and the fuzz targets share it.
//
// A field's bytes, byte..byte+span()-1, are read as one integer in its byte order (little:
// the first byte least significant; big: the first byte most significant); the field is that
// integer's bits bit..bit+bits-1, counted from its least significant bit. For a little-endian
// field this is HID's own bit order (bit b of byte k is bit 8k + b of the message).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace hapticd::drivers::field {

// The whole-byte types a layout names with `type:`. The first seven keep their numbers (the
// fuzz corpus is written with them).
enum class FieldType : std::uint8_t { kU8, kI8, kU16, kI16, kU32, kI32, kF32, kU24, kI24 };
enum class Endian : std::uint8_t { kLittle, kBig };

// "u8", "i16", "f32", "u24"...
std::string_view to_string(FieldType type) noexcept;
std::optional<FieldType> parse_field_type(std::string_view text) noexcept;

// Widest integer field: its raw values are exact in a double and in an int64.
inline constexpr unsigned kMaxFieldBits = 32;

struct FieldSpec {
  std::size_t byte = 0;    // offset in the message (a HID report's: after the report id)
  unsigned bit = 0;        // 0..7: the field's lowest bit in the integer its bytes make
  unsigned bits = 8;       // 1..32 (an f32: 32)
  bool is_signed = false;  // two's complement of `bits`
  bool is_float = false;   // IEEE 754 single precision (bit 0, 32 bits)
  Endian endian = Endian::kLittle;
  double scale = 1.0;   // SI units per count
  double offset = 0.0;  // SI units at raw 0

  // Bytes the field touches, and the first byte past them.
  std::size_t span() const noexcept { return (bit + bits + 7) / 8; }
  std::size_t end() const noexcept { return byte + span(); }
  // Which bits of data byte `k` the field uses (0 for a byte it does not touch).
  std::uint8_t mask_of_byte(std::size_t k) const noexcept;
};

// A field of a whole-byte type at `byte`.
FieldSpec typed(FieldType type, std::size_t byte = 0, Endian endian = Endian::kLittle,
                double scale = 1.0, double offset = 0.0) noexcept;

// "u8", "i16", "f32", "u12", "i24": what the field holds.
std::string type_name(const FieldSpec& f);
inline bool is_integer(const FieldSpec& f) noexcept { return !f.is_float; }
// The range of raw values the field holds (f32: +-FLT_MAX).
double raw_min(const FieldSpec& f) noexcept;
double raw_max(const FieldSpec& f) noexcept;
// 2^bits for an unsigned integer field (the wrap of a counter in it); 0 for the others.
std::uint64_t counter_modulus(const FieldSpec& f) noexcept;

// RT-safe: called every tick. The raw value of field `f` of `data` (the message: a report's data
// after its id; the caller has checked it holds f.end() bytes). Integers are exact; f32 is widened.
double read_raw(const std::uint8_t* data, const FieldSpec& f) noexcept;
// RT-safe: called every tick. An integer field's raw value (0 for an f32).
std::int64_t read_count(const std::uint8_t* data, const FieldSpec& f) noexcept;
// RT-safe: called every tick. Writes `raw` into field `f` of `data`, leaving the other bits of
// the bytes it shares untouched: rounded to nearest for integers and clamped to the field's
// range (a NaN writes 0).
void write_raw(std::uint8_t* data, const FieldSpec& f, double raw) noexcept;
// RT-safe. Writes integer `count` modulo 2^bits: a counter or a position that wraps.
void write_wrapped(std::uint8_t* data, const FieldSpec& f, std::int64_t count) noexcept;

// RT-safe: called every tick. SI value of the field in `data` (the message).
inline double read_si(const std::uint8_t* data, const FieldSpec& f) noexcept {
  return read_raw(data, f) * f.scale + f.offset;
}
// RT-safe: called every tick. Raw count for an SI value (not yet rounded or clamped).
inline double si_to_raw(double si, const FieldSpec& f) noexcept {
  return (si - f.offset) / f.scale;
}
// RT-safe: called every tick. Writes the SI value `si` into `data`.
inline void write_si(std::uint8_t* data, const FieldSpec& f, double si) noexcept {
  write_raw(data, f, si_to_raw(si, f));
}

}  // namespace hapticd::drivers::field
