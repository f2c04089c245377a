#include "drivers/hid/report_field.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace hapticd::drivers::hid {
namespace {

struct TypeInfo {
  std::string_view name;
  std::size_t size;
  bool is_signed;
  bool is_float;
};

constexpr std::array<TypeInfo, 7> kTypes{{{"u8", 1, false, false},
                                          {"i8", 1, true, false},
                                          {"u16", 2, false, false},
                                          {"i16", 2, true, false},
                                          {"u32", 4, false, false},
                                          {"i32", 4, true, false},
                                          {"f32", 4, true, true}}};

const TypeInfo& info(FieldType t) noexcept { return kTypes[static_cast<std::size_t>(t)]; }

std::uint32_t load(const std::uint8_t* b, std::size_t n, Endian e) noexcept {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = e == Endian::kLittle ? n - 1 - i : i;
    v = (v << 8) | b[at];
  }
  return v;
}

void store(std::uint8_t* b, std::size_t n, Endian e, std::uint32_t v) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = e == Endian::kLittle ? i : n - 1 - i;
    b[at] = static_cast<std::uint8_t>(v >> (8 * i));
  }
}

}  // namespace

std::string_view to_string(FieldType type) noexcept { return info(type).name; }

std::optional<FieldType> parse_field_type(std::string_view text) noexcept {
  for (std::size_t i = 0; i < kTypes.size(); ++i) {
    if (kTypes[i].name == text) return static_cast<FieldType>(i);
  }
  return std::nullopt;
}

std::size_t field_size(FieldType type) noexcept { return info(type).size; }
bool is_integer(FieldType type) noexcept { return !info(type).is_float; }

double raw_min(FieldType type) noexcept {
  const TypeInfo& t = info(type);
  if (t.is_float) return -static_cast<double>(FLT_MAX);
  if (!t.is_signed) return 0.0;
  return -std::ldexp(1.0, static_cast<int>(8 * t.size - 1));
}

double raw_max(FieldType type) noexcept {
  const TypeInfo& t = info(type);
  if (t.is_float) return static_cast<double>(FLT_MAX);
  return std::ldexp(1.0, static_cast<int>(8 * t.size - (t.is_signed ? 1 : 0))) - 1.0;
}

std::uint64_t counter_modulus(FieldType type) noexcept {
  const TypeInfo& t = info(type);
  if (t.is_float || t.is_signed) return 0;
  return std::uint64_t{1} << (8 * t.size);
}

double read_raw(const std::uint8_t* bytes, FieldType type, Endian endian) noexcept {
  const TypeInfo& t = info(type);
  const std::uint32_t u = load(bytes, t.size, endian);
  if (t.is_float) {
    float f;
    std::memcpy(&f, &u, sizeof f);
    return static_cast<double>(f);
  }
  if (!t.is_signed) return static_cast<double>(u);
  const unsigned bits = static_cast<unsigned>(8 * t.size);
  const std::uint32_t sign = std::uint32_t{1} << (bits - 1);
  // Two's complement of the field's own width, sign-extended.
  const std::int64_t v = static_cast<std::int64_t>(u ^ sign) - static_cast<std::int64_t>(sign);
  return static_cast<double>(v);
}

void write_raw(std::uint8_t* bytes, FieldType type, Endian endian, double raw) noexcept {
  const TypeInfo& t = info(type);
  if (t.is_float) {
    const float f =
        std::isnan(raw) ? 0.0f : static_cast<float>(std::clamp(raw, raw_min(type), raw_max(type)));
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    store(bytes, t.size, endian, u);
    return;
  }
  const double r =
      std::isnan(raw) ? 0.0 : std::clamp(std::nearbyint(raw), raw_min(type), raw_max(type));
  const auto v = static_cast<std::int64_t>(r);
  store(bytes, t.size, endian, static_cast<std::uint32_t>(v));
}

}  // namespace hapticd::drivers::hid
