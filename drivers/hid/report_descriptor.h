// The project's own HID report descriptor parser (HID 1.11 §6.2.2): short and long items, the
// global state with Push/Pop, local usages (single, extended and ranges), collections, and
// Input/Output/Feature main items. It yields every report (kind and id, size) and every field
// (bit position, size, count, logical and physical range, usages, the usages of the
// collections around it), which is what the PID profile needs to find its reports by usage
// rather than by id. Pure code; a malformed or absurd descriptor is an error with the byte
// offset named, never a crash (see the fuzz target and tests/hid).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace hapticd::drivers::hid {

// Linux's HID_MAX_DESCRIPTOR_SIZE: no device has a longer one.
inline constexpr std::size_t kMaxDescriptorSize = 4096;

enum class ReportKind : std::uint8_t { kInput, kOutput, kFeature };
const char* to_string(ReportKind kind) noexcept;

// A usage with its page: page << 16 | id.
constexpr std::uint32_t usage(std::uint16_t page, std::uint16_t id) noexcept {
  return static_cast<std::uint32_t>(page) << 16 | id;
}
constexpr std::uint16_t usage_page_of(std::uint32_t u) noexcept {
  return static_cast<std::uint16_t>(u >> 16);
}

// Bits of a main item's data (HID 1.11 §6.2.2.5).
enum MainFlag : std::uint32_t {
  kMainConstant = 1u << 0,  // else data
  kMainVariable = 1u << 1,  // else array
  kMainRelative = 1u << 2,
  kMainNullState = 1u << 6,
};

struct ReportField {
  ReportKind kind = ReportKind::kInput;
  std::uint8_t report_id = 0;
  std::uint32_t bit_offset = 0;  // from the start of the report's data (after the id)
  std::uint32_t bit_size = 0;    // Report Size
  std::uint32_t count = 0;       // Report Count
  std::uint32_t flags = 0;       // MainFlag bits
  std::int64_t logical_min = 0, logical_max = 0;
  std::int64_t physical_min = 0, physical_max = 0;  // both 0: none given
  // Variable field: the usage of element i is usages[min(i, size-1)]. Array field: the usages
  // its elements select from, in order (element value logical_min + i selects usages[i]).
  std::vector<std::uint32_t> usages;
  // The usages of the collections around the field, outermost first.
  std::vector<std::uint32_t> collections;

  bool is_constant() const noexcept { return (flags & kMainConstant) != 0; }
  bool is_variable() const noexcept { return (flags & kMainVariable) != 0; }
  bool is_signed() const noexcept { return logical_min < 0; }
  // The usage of element `i` of a variable field (0 when the field has none).
  std::uint32_t usage_of(std::uint32_t i) const noexcept;
  bool inside(std::uint32_t collection_usage) const noexcept;
};

struct ReportInfo {
  ReportKind kind = ReportKind::kInput;
  std::uint8_t id = 0;
  std::uint32_t bits = 0;  // data bits, without the id
  std::size_t data_bytes() const noexcept { return (bits + 7) / 8; }
};

struct ParsedDescriptor {
  std::vector<ReportField> fields;
  std::vector<ReportInfo> reports;
  bool numbered = false;  // the device uses report ids
  // Top-level application collections' usages, in order.
  std::vector<std::uint32_t> applications;

  const ReportInfo* find_report(ReportKind kind, std::uint8_t id) const noexcept;
};

struct DescriptorParse {
  std::optional<ParsedDescriptor> descriptor;
  std::string error;  // "byte 12: ..." when descriptor is empty
};

// Not RT-safe (allocates). Never throws for any input but std::bad_alloc.
DescriptorParse parse_report_descriptor(std::span<const std::uint8_t> bytes);

// RT-safe: called every tick. Bits [bit_offset, bit_offset + bits) of `data` (little-endian bit
// order, as HID packs them), bits <= 32; bits past `data` read as 0.
std::uint32_t get_bits(std::span<const std::uint8_t> data, std::uint32_t bit_offset,
                       std::uint32_t bits) noexcept;
// RT-safe: called every tick. Sets those bits to the low `bits` of `value`; bits past `data` are
// not written.
void put_bits(std::span<std::uint8_t> data, std::uint32_t bit_offset, std::uint32_t bits,
              std::uint32_t value) noexcept;
// The value as the field's logical range reads it: sign-extended when logical_min < 0.
std::int64_t field_value(std::uint32_t raw, std::uint32_t bits, bool is_signed) noexcept;

}  // namespace hapticd::drivers::hid
