#include "config/schema_reader.h"

#include "base/hex.h"
#include "config/config_loader.h"  // kMaxMessages

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <utility>

namespace hapticd::config::schema {
namespace {

std::string quoted(const std::string& text) { return "'" + text + "'"; }

std::string to_lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

// Optimal string alignment distance: Levenshtein plus adjacent transpositions, so
// "stiffnses" is one edit from "stiffness".
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const std::size_t w = b.size() + 1;
  std::vector<std::size_t> d((a.size() + 1) * w);
  for (std::size_t i = 0; i <= a.size(); ++i) d[i * w] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      std::size_t best =
          std::min({d[(i - 1) * w + j] + 1, d[i * w + j - 1] + 1, d[(i - 1) * w + j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        best = std::min(best, d[(i - 2) * w + j - 2] + 1);
      }
      d[i * w + j] = best;
    }
  }
  return d[a.size() * w + b.size()];
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
  const std::string lower = to_lower(body);
  if (lower == ".inf" || lower == ".nan") return Parsed::kNotFinite;
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

std::string printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 0xf];
    } else {
      out += c;
    }
  }
  return out;
}

std::string child_path(const std::string& parent, std::string_view key) {
  if (parent.empty()) return std::string(key);
  std::string out = parent;
  out += '.';
  out += key;
  return out;
}

std::string describe_value(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return quoted(node.Scalar());
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    default:
      return "nothing";
  }
}

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

// ---------------------------------------------------------------------------- Diagnostics

void Diagnostics::set_origin(const std::string& path, const std::string& text, std::size_t order) {
  // A later --set of an enclosing key replaces whatever earlier ones put below it.
  std::erase_if(origins_, [&](const Origin& o) {
    return o.path == path || (o.path.size() > path.size() && o.path.starts_with(path) &&
                              (o.path[path.size()] == '.' || o.path[path.size()] == '['));
  });
  origins_.push_back({path, text, order});
}

const Diagnostics::Origin* Diagnostics::origin_of(const std::string& path) const {
  const Origin* best = nullptr;
  for (const Origin& o : origins_) {
    const bool covers =
        path == o.path || (path.size() > o.path.size() && path.starts_with(o.path) &&
                           (path[o.path.size()] == '.' || path[o.path.size()] == '['));
    if (covers && (best == nullptr || o.path.size() > best->path.size())) best = &o;
  }
  return best;
}

void Diagnostics::add(Entry entry) {
  entry.text = printable(entry.text);
  entries_.push_back(std::move(entry));
}

std::string Diagnostics::where(const YAML::Mark& mark, const std::string& path) const {
  if (const Origin* o = origin_of(path)) return "--set " + o->text;
  std::string prefix = source_;
  if (mark.line >= 0) prefix += ":" + std::to_string(mark.line + 1);
  return prefix;
}

void Diagnostics::note_location(const YAML::Mark& mark, const std::string& path) {
  locations_[path] = where(mark, path);
}

void Diagnostics::error(const YAML::Mark& mark, const std::string& path, const std::string& what) {
  const std::string body = path.empty() ? what : path + ": " + what;
  if (const Origin* o = origin_of(path)) {
    add({true, o->order, 0, 0, "--set " + o->text + ": " + body});
    return;
  }
  add({false, 0, mark.line, mark.column, where(mark, path) + ": " + body});
}

void Diagnostics::set_error(const std::string& text, std::size_t order, const std::string& path,
                            const std::string& what) {
  add({true, order, 0, 0, "--set " + text + ": " + (path.empty() ? what : path + ": " + what)});
}

std::vector<std::string> Diagnostics::messages() const {
  std::vector<const Entry*> order;
  for (const Entry& e : entries_) order.push_back(&e);
  std::stable_sort(order.begin(), order.end(), [](const Entry* a, const Entry* b) {
    if (a->from_set != b->from_set) return !a->from_set;
    if (a->from_set) return a->set_order < b->set_order;
    if (a->line != b->line) return a->line < b->line;
    return a->column < b->column;
  });
  std::vector<std::string> out;
  for (const Entry* e : order) {
    if (out.size() == kMaxMessages) {
      // Named like every other line, so a reader of several tools' output knows whose.
      out.push_back(source_ + ": ... and " + std::to_string(order.size() - kMaxMessages) +
                    " more problems not shown");
      break;
    }
    out.push_back(e->text);
  }
  return out;
}

// ------------------------------------------------------------------------------ MapReader

MapReader::MapReader(Diagnostics& diag, const Field& field)
    : diag_(diag), path_(field.path), mark_(field.key_mark) {
  if (!field.present || field.node.IsNull()) return;
  if (!field.node.IsMap()) {
    diag_.error(mark_, path_,
                path_.empty() ? "the top level must be a mapping" : "must be a mapping");
    ok_ = false;
    return;
  }
  for (auto it = field.node.begin(); it != field.node.end(); ++it) {
    // Copies: yaml-cpp's iterator -> yields a proxy temporary, so a reference would dangle.
    const YAML::Node key = it->first;
    const YAML::Node value = it->second;
    std::string name = key.IsScalar() ? key.Scalar() : "<" + describe_value(key) + " as key>";
    if (const Entry* first = find(name)) {
      // yaml-cpp keeps both entries and lookups see only the first: say so rather than
      // silently ignore the second.
      diag_.error(key.Mark(), child_path(path_, name),
                  "duplicate key (first at line " + std::to_string(first->mark.line + 1) + ")");
      continue;
    }
    index_.emplace(name, entries_.size());
    entries_.push_back({std::move(name), key.Mark(), value, false});
  }
}

MapReader::Entry* MapReader::find(std::string_view key) {
  const auto it = index_.find(std::string(key));
  return it == index_.end() ? nullptr : &entries_[it->second];
}

Field MapReader::take(std::string_view key) {
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.emplace_back(key);
  if (Entry* e = find(key)) {
    e->consumed = true;
    std::string path = child_path(path_, key);
    diag_.note_location(e->mark, path);
    return {std::move(path), e->value, e->mark, true};
  }
  return {child_path(path_, key), YAML::Node(), mark_, false};
}

void MapReader::missing(std::string_view key, const std::string& reason) {
  if (ok_) diag_.error(mark_, child_path(path_, key), "missing (" + reason + ")");
}

void MapReader::not_used(std::string_view key, const std::string& reason) {
  if (Entry* e = find(key)) {
    e->consumed = true;
    // An explicit null (`--set device.can=null`) says "none": another driver's section can be
    // switched off from the command line to compare drivers on one file.
    if (e->value.IsNull()) return;
    diag_.error(e->mark, child_path(path_, key), "not used by " + reason);
  }
}

void MapReader::finish() {
  for (Entry& e : entries_) {
    if (e.consumed) continue;
    e.consumed = true;
    diag_.error(e.mark, child_path(path_, e.key), unknown_key_message(e.key, known_));
  }
}

void MapReader::skip_rest() {
  for (Entry& e : entries_) e.consumed = true;
}

std::string unknown_key_message(std::string_view key, const std::vector<std::string>& expected) {
  const std::string lower = to_lower(key);
  const std::string* best = nullptr;
  std::size_t best_distance = 3;  // suggest only within two edits
  for (const std::string& candidate : expected) {
    const std::size_t d = edit_distance(lower, to_lower(candidate));
    if (d < best_distance) {
      best_distance = d;
      best = &candidate;
    }
  }
  if (best != nullptr) return "unknown key (did you mean '" + *best + "'?)";
  if (expected.empty()) return "unknown key";
  std::string out = "unknown key; expected one of: ";
  for (std::size_t i = 0; i < expected.size(); ++i) out += (i ? ", " : "") + expected[i];
  return out;
}

// -------------------------------------------------------------------------------- Values

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

std::optional<std::vector<double>> read_number_list(Diagnostics& diag, const Field& field) {
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
    if (auto v = read_number(diag, f)) {
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
