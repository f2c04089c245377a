#include "drivers/field/field.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace hapticd::drivers::field {
namespace {

struct TypeInfo {
  std::string_view name;
  unsigned bits;
  bool is_signed;
  bool is_float;
};

constexpr std::array<TypeInfo, 9> kTypes{{{"u8", 8, false, false},
                                          {"i8", 8, true, false},
                                          {"u16", 16, false, false},
                                          {"i16", 16, true, false},
                                          {"u32", 32, false, false},
                                          {"i32", 32, true, false},
                                          {"f32", 32, true, true},
                                          {"u24", 24, false, false},
                                          {"i24", 24, true, false}}};

const TypeInfo& info(FieldType t) noexcept { return kTypes[static_cast<std::size_t>(t)]; }

std::uint64_t low_bits(unsigned n) noexcept {
  return n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1;
}

// The field's bytes as one integer in its byte order (span() <= 5 bytes).
std::uint64_t load(const std::uint8_t* data, const FieldSpec& f) noexcept {
  const std::size_t n = f.span();
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = f.endian == Endian::kLittle ? n - 1 - i : i;
    v = (v << 8) | data[f.byte + at];
  }
  return v;
}

void store(std::uint8_t* data, const FieldSpec& f, std::uint64_t v) noexcept {
  const std::size_t n = f.span();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = f.endian == Endian::kLittle ? i : n - 1 - i;
    data[f.byte + at] = static_cast<std::uint8_t>(v >> (8 * i));
  }
}

// The field's raw bits (its low `bits`), put in place without touching its neighbours'.
void store_bits(std::uint8_t* data, const FieldSpec& f, std::uint64_t raw) noexcept {
  const std::uint64_t mask = low_bits(f.bits) << f.bit;
  const std::uint64_t word = (load(data, f) & ~mask) | ((raw << f.bit) & mask);
  store(data, f, word);
}

std::uint64_t raw_bits(const std::uint8_t* data, const FieldSpec& f) noexcept {
  return (load(data, f) >> f.bit) & low_bits(f.bits);
}

}  // namespace

std::string_view to_string(FieldType type) noexcept { return info(type).name; }

std::optional<FieldType> parse_field_type(std::string_view text) noexcept {
  for (std::size_t i = 0; i < kTypes.size(); ++i) {
    if (kTypes[i].name == text) return static_cast<FieldType>(i);
  }
  return std::nullopt;
}

FieldSpec typed(FieldType type, std::size_t byte, Endian endian, double scale,
                double offset) noexcept {
  const TypeInfo& t = info(type);
  FieldSpec f;
  f.byte = byte;
  f.bits = t.bits;
  f.is_signed = t.is_signed;
  f.is_float = t.is_float;
  f.endian = endian;
  f.scale = scale;
  f.offset = offset;
  return f;
}

std::uint8_t FieldSpec::mask_of_byte(std::size_t k) const noexcept {
  if (k < byte || k >= end()) return 0;
  const std::size_t n = span();
  // Which byte of the integer (0: least significant) data byte k is.
  const std::size_t j = endian == Endian::kLittle ? k - byte : n - 1 - (k - byte);
  const std::uint64_t field = low_bits(bits) << bit;
  return static_cast<std::uint8_t>(field >> (8 * j));
}

std::string type_name(const FieldSpec& f) {
  if (f.is_float) return "f32";
  return (f.is_signed ? "i" : "u") + std::to_string(f.bits);
}

double raw_min(const FieldSpec& f) noexcept {
  if (f.is_float) return -static_cast<double>(FLT_MAX);
  if (!f.is_signed) return 0.0;
  return -std::ldexp(1.0, static_cast<int>(f.bits) - 1);
}

double raw_max(const FieldSpec& f) noexcept {
  if (f.is_float) return static_cast<double>(FLT_MAX);
  return std::ldexp(1.0, static_cast<int>(f.bits) - (f.is_signed ? 1 : 0)) - 1.0;
}

std::uint64_t counter_modulus(const FieldSpec& f) noexcept {
  if (f.is_float || f.is_signed) return 0;
  return std::uint64_t{1} << f.bits;
}

std::int64_t read_count(const std::uint8_t* data, const FieldSpec& f) noexcept {
  if (f.is_float) return 0;
  const std::uint64_t u = raw_bits(data, f);
  if (!f.is_signed || f.bits == 0) return static_cast<std::int64_t>(u);
  // Two's complement of the field's own width, sign-extended.
  const std::uint64_t sign = std::uint64_t{1} << (f.bits - 1);
  return static_cast<std::int64_t>(u ^ sign) - static_cast<std::int64_t>(sign);
}

double read_raw(const std::uint8_t* data, const FieldSpec& f) noexcept {
  if (!f.is_float) return static_cast<double>(read_count(data, f));
  const auto u = static_cast<std::uint32_t>(raw_bits(data, f));
  float v;
  std::memcpy(&v, &u, sizeof v);
  return static_cast<double>(v);
}

void write_raw(std::uint8_t* data, const FieldSpec& f, double raw) noexcept {
  if (f.is_float) {
    const float v =
        std::isnan(raw) ? 0.0f : static_cast<float>(std::clamp(raw, raw_min(f), raw_max(f)));
    std::uint32_t u;
    std::memcpy(&u, &v, sizeof u);
    store_bits(data, f, u);
    return;
  }
  const double r = std::isnan(raw) ? 0.0 : std::clamp(std::nearbyint(raw), raw_min(f), raw_max(f));
  store_bits(data, f, static_cast<std::uint64_t>(static_cast<std::int64_t>(r)));
}

void write_wrapped(std::uint8_t* data, const FieldSpec& f, std::int64_t count) noexcept {
  if (f.is_float) return;
  store_bits(data, f, static_cast<std::uint64_t>(count));  // two's complement: modulo 2^bits
}

}  // namespace hapticd::drivers::field
