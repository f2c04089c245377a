// The value readers of the schema (schema_reader.h): numbers, integers, booleans, strings,
// lists and hexadecimal ids, each refusing a wrong value with one message that echoes it.
#include "base/hex.h"
#include "config/schema_reader.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>

namespace hapticd::config::schema {
namespace {

// Equal but for the case of ASCII letters.
bool same_letters(std::string_view a, std::string_view b) {
  return std::ranges::equal(a, b, [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) ==
           std::tolower(static_cast<unsigned char>(y));
  });
}

enum class Parsed { kOk, kNotNumber, kNotFinite, kUnderflow };

// YAML 1.2 core-schema reals plus the special values, which are recognised so they can be
// refused with a precise message.
Parsed parse_number(const std::string& text, double& out) {
  std::string_view s(text);
  if (!s.empty() && s.front() == '+') {
    s.remove_prefix(1);
    if (!s.empty() && (s.front() == '+' || s.front() == '-')) return Parsed::kNotNumber;
  }
  std::string_view body = s;
  if (!body.empty() && body.front() == '-') body.remove_prefix(1);
  if (same_letters(body, ".inf") || same_letters(body, ".nan")) return Parsed::kNotFinite;
  if (s.empty()) return Parsed::kNotNumber;
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ptr != s.data() + s.size()) return Parsed::kNotNumber;
  if (ec == std::errc::result_out_of_range) {
    // from_chars does not say whether it overflowed or underflowed; strtod does. An underflow
    // would silently become 0 (or lose its precision as a subnormal): refuse it instead.
    v = std::strtod(std::string(s).c_str(), nullptr);
    if (std::isfinite(v)) return Parsed::kUnderflow;
  } else if (ec != std::errc()) {
    return Parsed::kNotNumber;
  }
  if (!std::isfinite(v)) return Parsed::kNotFinite;
  out = v;
  return Parsed::kOk;
}

bool is_decimal_integer(std::string_view s) {
  if (!s.empty() && (s.front() == '-' || s.front() == '+')) s.remove_prefix(1);
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::string describe_int_range(const IntRange& r, bool below) {
  if (!r.open_top) return "in " + std::to_string(r.lo) + ".." + std::to_string(r.hi);
  return below ? ">= " + std::to_string(r.lo) : "<= " + std::to_string(r.hi);
}

}  // namespace

bool parse_finite(const std::string& text, double& out) {
  return parse_number(text, out) == Parsed::kOk;
}

std::string format_number(double value) {
  char buf[64];
  const double mag = std::fabs(value);
  const auto fmt = (mag == 0.0 || (mag >= 1e-4 && mag < 1e15)) ? std::chars_format::fixed
                                                               : std::chars_format::general;
  const auto result = std::to_chars(buf, buf + sizeof buf, value, fmt);
  return std::string(buf, result.ptr);
}

bool Range::contains(double v) const {
  if (lo_kind == Bound::kOpen && !(v > lo)) return false;
  if (lo_kind == Bound::kClosed && !(v >= lo)) return false;
  if (hi_kind == Bound::kOpen && !(v < hi)) return false;
  if (hi_kind == Bound::kClosed && !(v <= hi)) return false;
  return true;
}

std::string Range::describe() const {
  if (lo_kind != Bound::kNone && hi_kind != Bound::kNone) {
    return std::string("in ") + (lo_kind == Bound::kClosed ? "[" : "(") + format_number(lo) + ", " +
           format_number(hi) + (hi_kind == Bound::kClosed ? "]" : ")");
  }
  if (lo_kind != Bound::kNone)
    return (lo_kind == Bound::kClosed ? ">= " : "> ") + format_number(lo);
  if (hi_kind != Bound::kNone)
    return (hi_kind == Bound::kClosed ? "<= " : "< ") + format_number(hi);
  return "a number";
}

std::optional<double> read_number(Diagnostics& diag, const Field& field, const Range& range) {
  if (!field.present) return std::nullopt;
  if (!field.node.IsScalar()) {
    diag.error(field.key_mark, field.path, "must be a number, got " + describe_value(field.node));
    return std::nullopt;
  }
  const std::string& text = field.node.Scalar();
  double v = 0.0;
  switch (parse_number(text, v)) {
    case Parsed::kNotNumber:
      diag.error(field.key_mark, field.path, "must be a number, got " + quoted(text));
      return std::nullopt;
    case Parsed::kNotFinite:
      diag.error(field.key_mark, field.path, "must be a finite number, got " + quoted(text));
      return std::nullopt;
    case Parsed::kUnderflow:
      diag.error(field.key_mark, field.path,
                 "is too close to zero to be represented (it would become 0), got " + quoted(text));
      return std::nullopt;
    case Parsed::kOk:
      break;
  }
  if (!range.contains(v)) {
    diag.error(field.key_mark, field.path, "must be " + range.describe() + ", got " + quoted(text));
    return std::nullopt;
  }
  return v;
}

std::optional<long long> read_integer(Diagnostics& diag, const Field& field,
                                      const IntRange& range) {
  if (!field.present) return std::nullopt;
  if (!field.node.IsScalar()) {
    diag.error(field.key_mark, field.path, "must be an integer, got " + describe_value(field.node));
    return std::nullopt;
  }
  const std::string& text = field.node.Scalar();
  if (!is_decimal_integer(text)) {
    diag.error(field.key_mark, field.path, "must be an integer, got " + quoted(text));
    return std::nullopt;
  }
  std::string_view s(text);
  if (s.front() == '+') s.remove_prefix(1);
  long long v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  const bool negative = s.front() == '-';
  if (ec == std::errc::result_out_of_range || v < range.lo || v > range.hi) {
    const bool below = ec == std::errc::result_out_of_range ? negative : v < range.lo;
    diag.error(field.key_mark, field.path,
               "must be " + describe_int_range(range, below) + ", got " + quoted(text));
    return std::nullopt;
  }
  return v;
}

std::optional<bool> read_bool(Diagnostics& diag, const Field& field) {
  if (!field.present) return std::nullopt;
  bool v = false;
  if (field.node.IsScalar() && YAML::convert<bool>::decode(field.node, v)) return v;
  diag.error(field.key_mark, field.path,
             "must be true or false, got " + describe_value(field.node));
  return std::nullopt;
}

std::optional<std::string> read_string(Diagnostics& diag, const Field& field) {
  if (!field.present) return std::nullopt;
  if (field.node.IsNull()) return std::string();
  if (field.node.IsScalar()) return field.node.Scalar();
  diag.error(field.key_mark, field.path, "must be a string, got " + describe_value(field.node));
  return std::nullopt;
}

std::optional<std::size_t> read_choice(Diagnostics& diag, const Field& field,
                                       const std::vector<std::string>& choices) {
  if (!field.present) return std::nullopt;
  if (field.node.IsScalar()) {
    const auto it = std::find(choices.begin(), choices.end(), field.node.Scalar());
    if (it != choices.end()) return static_cast<std::size_t>(it - choices.begin());
  }
  std::string what = "must be one of ";
  for (std::size_t i = 0; i < choices.size(); ++i) what += (i ? ", " : "") + choices[i];
  diag.error(field.key_mark, field.path, what + "; got " + describe_value(field.node));
  return std::nullopt;
}

std::optional<std::vector<double>> read_number_list(Diagnostics& diag, const Field& field,
                                                    const Range& range) {
  if (!field.present) return std::nullopt;
  if (field.node.IsNull() || (field.node.IsSequence() && field.node.size() == 0)) {
    diag.error(field.key_mark, field.path, "must be a non-empty list of numbers");
    return std::nullopt;
  }
  if (!field.node.IsSequence()) {
    diag.error(field.key_mark, field.path, "must be a list of numbers");
    return std::nullopt;
  }
  std::vector<double> out;
  bool ok = true;
  for (std::size_t i = 0; i < field.node.size(); ++i) {
    const YAML::Node element = field.node[i];
    const Field f{field.path + "[" + std::to_string(i) + "]", element, element.Mark(), true};
    if (auto v = read_number(diag, f, range)) {
      out.push_back(*v);
    } else {
      ok = false;
    }
  }
  if (!ok) return std::nullopt;
  return out;
}

std::optional<std::uint32_t> read_hex(Diagnostics& diag, const Field& field, std::uint32_t max) {
  if (!field.present) return std::nullopt;
  const std::string text = field.node.IsScalar() ? field.node.Scalar() : std::string();
  std::string_view s(text);
  int radix = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    s.remove_prefix(2);
    radix = 16;
  }
  std::uint64_t v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v, radix);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size() || v > max) {
    diag.error(field.key_mark, field.path,
               "must be an integer in 0.." + std::to_string(max) + " (" + base::hex(max) +
                   "), decimal or 0x hexadecimal, got " + describe_value(field.node));
    return std::nullopt;
  }
  return static_cast<std::uint32_t>(v);
}

void number(MapReader& map, const Field& field, const Range& range, double& out) {
  if (const auto v = read_number(map.diag(), field, range)) out = *v;
}

}  // namespace hapticd::config::schema
