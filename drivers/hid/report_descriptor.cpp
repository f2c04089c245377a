#include "drivers/hid/report_descriptor.h"

#include <algorithm>

#include "base/hex.h"

namespace hapticd::drivers::hid {
namespace {

// Bounds that no real device comes near; past them a descriptor is refused, not followed.
constexpr std::size_t kMaxFields = 1024;
constexpr std::size_t kMaxDepth = 64;
constexpr std::size_t kMaxPush = 16;
constexpr std::size_t kMaxUsages = 4096;
constexpr std::uint32_t kMaxReportSize = 256;    // bits per element (Linux's limit)
constexpr std::uint32_t kMaxReportCount = 4096;  // elements per main item
constexpr std::uint64_t kMaxReportBits = 4096 * 8;

enum ItemType : std::uint8_t { kMain = 0, kGlobal = 1, kLocal = 2, kReserved = 3 };

// An item's data as it was written: the reading (signed or not) depends on the item.
struct Raw {
  std::uint32_t value = 0;
  std::uint8_t size = 0;
  std::int64_t as_signed() const noexcept {
    if (size == 0) return 0;
    const unsigned bits = 8u * size;
    if (bits >= 32) return static_cast<std::int32_t>(value);
    const std::uint32_t sign = 1u << (bits - 1);
    return static_cast<std::int64_t>(value ^ sign) - static_cast<std::int64_t>(sign);
  }
};

struct Globals {
  std::uint16_t page = 0;
  Raw lmin, lmax, pmin, pmax;
  std::uint32_t report_size = 0, report_count = 0;
  std::uint8_t report_id = 0;
};

struct LocalUsage {
  std::uint32_t value;
  bool extended;  // 4-byte usage: carries its own page
};

class Parser {
 public:
  explicit Parser(std::span<const std::uint8_t> b) : bytes_(b) {}
  DescriptorParse run();

 private:
  bool fail(std::size_t at, const std::string& what) {
    error_ = "byte " + std::to_string(at) + ": " + what;
    return false;
  }
  bool item(std::uint8_t type, std::uint8_t tag, Raw data, std::size_t at);
  bool main_item(std::uint8_t tag, Raw data, std::size_t at);
  bool global_item(std::uint8_t tag, Raw data, std::size_t at);
  bool local_item(std::uint8_t tag, Raw data, std::size_t at);
  bool add_field(ReportKind kind, std::uint32_t flags, std::size_t at);
  std::uint32_t resolve(const LocalUsage& u) const noexcept {
    return u.extended ? u.value : usage(g_.page, static_cast<std::uint16_t>(u.value));
  }

  std::span<const std::uint8_t> bytes_;
  Globals g_;
  std::vector<Globals> stack_;
  std::vector<LocalUsage> usages_;
  std::optional<LocalUsage> usage_min_;
  std::vector<std::uint32_t> collections_;
  ParsedDescriptor out_;
  std::string error_;
};

DescriptorParse Parser::run() {
  if (bytes_.empty()) return {std::nullopt, "the report descriptor is empty"};
  if (bytes_.size() > kMaxDescriptorSize) {
    return {std::nullopt, "the report descriptor is " + std::to_string(bytes_.size()) +
                              " bytes, more than any device has (" +
                              std::to_string(kMaxDescriptorSize) + ")"};
  }
  std::size_t pos = 0;
  while (pos < bytes_.size()) {
    const std::size_t at = pos;
    const std::uint8_t prefix = bytes_[pos++];
    if (prefix == 0xFE) {  // long item: size, tag, data; no long items are defined
      if (pos + 2 > bytes_.size())
        return {std::nullopt, "byte " + std::to_string(at) + ": long item cut short"};
      const std::size_t size = bytes_[pos];
      pos += 2;
      if (pos + size > bytes_.size()) {
        return {std::nullopt, "byte " + std::to_string(at) + ": long item cut short"};
      }
      pos += size;
      continue;
    }
    const std::size_t size = (prefix & 3) == 3 ? 4 : (prefix & 3);
    if (pos + size > bytes_.size()) {
      return {std::nullopt, "byte " + std::to_string(at) + ": item " +
                                base::hex(prefix, 2, base::HexCase::kLower) + " needs " +
                                std::to_string(size) + " data bytes; the descriptor ends first"};
    }
    Raw data{0, static_cast<std::uint8_t>(size)};
    for (std::size_t i = 0; i < size; ++i) data.value |= std::uint32_t{bytes_[pos + i]} << (8 * i);
    pos += size;
    if (!item(static_cast<std::uint8_t>((prefix >> 2) & 3), prefix >> 4, data, at)) {
      return {std::nullopt, error_};
    }
  }
  if (!collections_.empty()) {
    return {std::nullopt, std::to_string(collections_.size()) +
                              " collection(s) still open at the end of the descriptor"};
  }
  if (out_.numbered) {
    for (const ReportInfo& r : out_.reports) {
      if (r.id == 0) {
        return {std::nullopt, std::string("a ") + to_string(r.kind) +
                                  " report has fields before any Report ID, in a descriptor "
                                  "that numbers its reports"};
      }
    }
  }
  return {std::move(out_), ""};
}

bool Parser::item(std::uint8_t type, std::uint8_t tag, Raw data, std::size_t at) {
  switch (type) {
    case kMain:
      return main_item(tag, data, at);
    case kGlobal:
      return global_item(tag, data, at);
    case kLocal:
      return local_item(tag, data, at);
    default:
      return true;  // reserved item type: nothing defined, skipped as Linux does
  }
}

bool Parser::main_item(std::uint8_t tag, Raw data, std::size_t at) {
  bool ok = true;
  switch (tag) {
    case 0x8:
      ok = add_field(ReportKind::kInput, data.value, at);
      break;
    case 0x9:
      ok = add_field(ReportKind::kOutput, data.value, at);
      break;
    case 0xB:
      ok = add_field(ReportKind::kFeature, data.value, at);
      break;
    case 0xA: {  // Collection: its usage is the first local usage
      if (collections_.size() >= kMaxDepth) return fail(at, "collections nested too deep");
      const std::uint32_t u = usages_.empty() ? 0 : resolve(usages_.front());
      if (collections_.empty() && data.value == 1) out_.applications.push_back(u);
      collections_.push_back(u);
      break;
    }
    case 0xC:
      if (collections_.empty()) return fail(at, "End Collection without a Collection");
      collections_.pop_back();
      break;
    default:
      return fail(at, "unknown main item tag " + std::to_string(tag));
  }
  usages_.clear();
  usage_min_.reset();
  return ok;
}

bool Parser::global_item(std::uint8_t tag, Raw data, std::size_t at) {
  switch (tag) {
    case 0x0:
      g_.page = static_cast<std::uint16_t>(data.value);
      return true;
    case 0x1:
      g_.lmin = data;
      return true;
    case 0x2:
      g_.lmax = data;
      return true;
    case 0x3:
      g_.pmin = data;
      return true;
    case 0x4:
      g_.pmax = data;
      return true;
    case 0x5:
    case 0x6:
      return true;  // unit exponent, unit: the profiles scale from the configuration
    case 0x7:
      if (data.value == 0 || data.value > kMaxReportSize) {
        return fail(at, "Report Size " + std::to_string(data.value) + " bits: must be 1.." +
                            std::to_string(kMaxReportSize));
      }
      g_.report_size = data.value;
      return true;
    case 0x8:
      if (data.value == 0 || data.value > 255) {
        return fail(at, "Report ID " + std::to_string(data.value) + ": must be 1..255");
      }
      g_.report_id = static_cast<std::uint8_t>(data.value);
      out_.numbered = true;
      return true;
    case 0x9:
      if (data.value > kMaxReportCount) {
        return fail(at, "Report Count " + std::to_string(data.value) + ": more than " +
                            std::to_string(kMaxReportCount));
      }
      g_.report_count = data.value;
      return true;
    case 0xA:
      if (stack_.size() >= kMaxPush) return fail(at, "Push nested too deep");
      stack_.push_back(g_);
      return true;
    case 0xB:
      if (stack_.empty()) return fail(at, "Pop without a Push");
      g_ = stack_.back();
      stack_.pop_back();
      return true;
    default:
      return fail(at, "unknown global item tag " + std::to_string(tag));
  }
}

bool Parser::local_item(std::uint8_t tag, Raw data, std::size_t at) {
  const LocalUsage u{data.value, data.size == 4};
  switch (tag) {
    case 0x0:
      if (usages_.size() >= kMaxUsages) return fail(at, "too many usages for one item");
      usages_.push_back(u);
      return true;
    case 0x1:
      usage_min_ = u;
      return true;
    case 0x2: {
      if (!usage_min_) return fail(at, "Usage Maximum without a Usage Minimum");
      const std::uint32_t lo =
          usage_min_->extended ? usage_min_->value & 0xFFFF : usage_min_->value;
      const std::uint32_t hi = u.extended ? u.value & 0xFFFF : u.value;
      if (hi < lo) return fail(at, "Usage Maximum below Usage Minimum");
      if (usages_.size() + (hi - lo + 1) > kMaxUsages) {
        return fail(at, "a usage range of " + std::to_string(hi - lo + 1) + " usages is too large");
      }
      const std::uint32_t page_bits = usage_min_->extended ? usage_min_->value & 0xFFFF0000u : 0;
      for (std::uint32_t v = lo; v <= hi; ++v)
        usages_.push_back({page_bits | v, usage_min_->extended});
      usage_min_.reset();
      return true;
    }
    default:
      return true;  // designators, strings, delimiters: not needed here
  }
}

bool Parser::add_field(ReportKind kind, std::uint32_t flags, std::size_t at) {
  if (g_.report_count == 0) return true;  // nothing in the report
  if (g_.report_size == 0)
    return fail(at, std::string(to_string(kind)) + " item with no Report Size");
  if (out_.fields.size() >= kMaxFields) return fail(at, "too many fields");
  auto it = std::find_if(out_.reports.begin(), out_.reports.end(), [&](const ReportInfo& r) {
    return r.kind == kind && r.id == g_.report_id;
  });
  if (it == out_.reports.end()) {
    out_.reports.push_back({kind, g_.report_id, 0});
    it = out_.reports.end() - 1;
  }
  const std::uint64_t bits = std::uint64_t{g_.report_size} * g_.report_count;
  if (it->bits + bits > kMaxReportBits) {
    return fail(at, std::string(to_string(kind)) + " report " + std::to_string(g_.report_id) +
                        " grows past " + std::to_string(kMaxReportBits / 8) + " bytes");
  }
  ReportField f;
  f.kind = kind;
  f.report_id = g_.report_id;
  f.bit_offset = it->bits;
  f.bit_size = g_.report_size;
  f.count = g_.report_count;
  f.flags = flags;
  f.logical_min = g_.lmin.as_signed();
  // A negative minimum makes the maximum signed too; otherwise it is read unsigned (Linux).
  f.logical_max =
      f.logical_min < 0 ? g_.lmax.as_signed() : static_cast<std::int64_t>(g_.lmax.value);
  f.physical_min = g_.pmin.as_signed();
  f.physical_max =
      f.physical_min < 0 ? g_.pmax.as_signed() : static_cast<std::int64_t>(g_.pmax.value);
  for (const LocalUsage& u : usages_) f.usages.push_back(resolve(u));
  f.collections = collections_;
  it->bits += static_cast<std::uint32_t>(bits);
  out_.fields.push_back(std::move(f));
  return true;
}

}  // namespace

const char* to_string(ReportKind kind) noexcept {
  switch (kind) {
    case ReportKind::kInput:
      return "input";
    case ReportKind::kOutput:
      return "output";
    case ReportKind::kFeature:
      return "feature";
  }
  return "unknown";
}

std::uint32_t ReportField::usage_of(std::uint32_t i) const noexcept {
  if (usages.empty()) return 0;
  return usages[std::min<std::size_t>(i, usages.size() - 1)];
}

bool ReportField::inside(std::uint32_t collection_usage) const noexcept {
  return std::find(collections.begin(), collections.end(), collection_usage) != collections.end();
}

const ReportInfo* ParsedDescriptor::find_report(ReportKind kind, std::uint8_t id) const noexcept {
  for (const ReportInfo& r : reports) {
    if (r.kind == kind && r.id == id) return &r;
  }
  return nullptr;
}

DescriptorParse parse_report_descriptor(std::span<const std::uint8_t> bytes) {
  return Parser(bytes).run();
}

std::uint32_t get_bits(std::span<const std::uint8_t> data, std::uint32_t bit_offset,
                       std::uint32_t bits) noexcept {
  std::uint32_t v = 0;
  for (std::uint32_t i = 0; i < bits && i < 32; ++i) {
    const std::uint64_t bit = std::uint64_t{bit_offset} + i;
    if (bit / 8 >= data.size()) break;
    v |= static_cast<std::uint32_t>((data[bit / 8] >> (bit % 8)) & 1u) << i;
  }
  return v;
}

void put_bits(std::span<std::uint8_t> data, std::uint32_t bit_offset, std::uint32_t bits,
              std::uint32_t value) noexcept {
  for (std::uint32_t i = 0; i < bits && i < 32; ++i) {
    const std::uint64_t bit = std::uint64_t{bit_offset} + i;
    if (bit / 8 >= data.size()) break;
    const auto mask = static_cast<std::uint8_t>(1u << (bit % 8));
    if ((value >> i) & 1u) {
      data[bit / 8] = static_cast<std::uint8_t>(data[bit / 8] | mask);
    } else {
      data[bit / 8] = static_cast<std::uint8_t>(data[bit / 8] & ~mask);
    }
  }
}

std::int64_t field_value(std::uint32_t raw, std::uint32_t bits, bool is_signed) noexcept {
  if (!is_signed || bits == 0 || bits >= 32) {
    return is_signed ? static_cast<std::int32_t>(raw) : static_cast<std::int64_t>(raw);
  }
  const std::uint32_t sign = 1u << (bits - 1);
  const std::uint32_t v = raw & ((sign << 1) - 1);
  return static_cast<std::int64_t>(v ^ sign) - static_cast<std::int64_t>(sign);
}

}  // namespace hapticd::drivers::hid
