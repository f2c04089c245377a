// One numeric field of a HID report, as a vendor layout puts it: a byte offset in the report's
// data (after the report id), a type, a byte order, and the affine map to SI units
// (SI = raw * scale + offset). Pure code: no OS headers, no allocation after construction,
// so the driver, its loopback peer and the fuzz targets share it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace hapticd::drivers::hid {

enum class FieldType : std::uint8_t { kU8, kI8, kU16, kI16, kU32, kI32, kF32 };
enum class Endian : std::uint8_t { kLittle, kBig };

// "u8", "i16", "f32"...
std::string_view to_string(FieldType type) noexcept;
std::optional<FieldType> parse_field_type(std::string_view text) noexcept;
// Bytes the type occupies.
std::size_t field_size(FieldType type) noexcept;
bool is_integer(FieldType type) noexcept;
// The range of raw values the type holds (f32: +-FLT_MAX).
double raw_min(FieldType type) noexcept;
double raw_max(FieldType type) noexcept;
// 2^bits for an unsigned integer type (the wrap of a counter in it); 0 for the others.
std::uint64_t counter_modulus(FieldType type) noexcept;

struct FieldSpec {
  std::size_t byte = 0;  // offset in the report's data, after the report id
  FieldType type = FieldType::kU8;
  Endian endian = Endian::kLittle;
  double scale = 1.0;   // SI units per count
  double offset = 0.0;  // SI units at raw 0

  std::size_t end() const noexcept { return byte + field_size(type); }
};

// RT-safe: called every tick. The raw value of a field whose bytes start at `bytes` (the caller has
// checked the report is long enough). Integers are exact; f32 is widened.
double read_raw(const std::uint8_t* bytes, FieldType type, Endian endian) noexcept;
// RT-safe: called every tick. Writes `raw`, rounded to nearest for integers and clamped to the
// type's range (a NaN writes 0).
void write_raw(std::uint8_t* bytes, FieldType type, Endian endian, double raw) noexcept;

// RT-safe: called every tick. SI value of the field in `data` (the report's data, after the id).
inline double read_si(const std::uint8_t* data, const FieldSpec& f) noexcept {
  return read_raw(data + f.byte, f.type, f.endian) * f.scale + f.offset;
}
// RT-safe: called every tick. Raw count for an SI value (not yet rounded or clamped).
inline double si_to_raw(double si, const FieldSpec& f) noexcept {
  return (si - f.offset) / f.scale;
}
// RT-safe: called every tick. Writes the SI value `si` into `data`.
inline void write_si(std::uint8_t* data, const FieldSpec& f, double si) noexcept {
  write_raw(data + f.byte, f.type, f.endian, si_to_raw(si, f));
}

}  // namespace hapticd::drivers::hid
