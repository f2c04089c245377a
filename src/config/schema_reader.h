// A small schema-walking reader over yaml-cpp nodes: it looks keys up by name, remembers
// which ones were consumed, checks types and ranges, and collects every error with the place
// it came from (a file line, or the --set argument that produced the node). The config
// library reads its sections with it, and each driver reads its own section (device.<driver>)
// with it, so every message has the same "FILE:LINE: key: what" form.
//
// There is one list of keys per section: the keys its reader take()s. A key in the document
// that no reader takes is reported as unknown (suggesting the taken ones), so a key can never
// be silently ignored; skip_rest() is the one explicit way to stop reading a section after an
// error that makes the rest meaningless has been reported.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace hapticd::config::schema {

// `text` safe to print on a terminal: control bytes (and DEL) become \xNN escapes, so a
// value echoed in a message cannot move the cursor, clear the screen or forge a line.
std::string printable(std::string_view text);

// 'text', as a message names a value or a key.
std::string quoted(const std::string& text);

// "a.b" + "c" -> "a.b.c"; "" + "c" -> "c".
std::string child_path(const std::string& parent, std::string_view key);

// What a wrong value was, for "got ...": 'its text', or "a list", "a mapping", "nothing".
std::string describe_value(const YAML::Node& node);

// A finite real in YAML notation ("1", "-2.5e3", "+.5"); false for anything else.
bool parse_finite(const std::string& text, double& out);

// Shortest text that reads back as the same double, in plain notation for ordinary magnitudes
// ("500", "-0.5", "1e-07").
std::string format_number(double value);

class Diagnostics {
 public:
  explicit Diagnostics(std::string source) : source_(std::move(source)) {}

  // Everything at or below `path` came from the --set argument `text` (the override numbered
  // `order`); messages about it carry that argument instead of a line.
  void set_origin(const std::string& path, const std::string& text, std::size_t order);

  // "SOURCE:LINE: path: what", or "--set ARG: path: what" when `path` came from a --set.
  void error(const YAML::Mark& mark, const std::string& path, const std::string& what);
  // A problem with applying a --set itself (its value is not YAML, its path is blocked).
  void set_error(const std::string& text, std::size_t order, const std::string& path,
                 const std::string& what);

  // Records where the key at `path` is, for Config::key_locations.
  void note_location(const YAML::Mark& mark, const std::string& path);
  const std::map<std::string, std::string, std::less<>>& locations() const { return locations_; }

  bool empty() const { return entries_.empty(); }
  // File messages in document order, then --set messages in command-line order; past
  // config::kMaxMessages, one last line says how many more there are.
  std::vector<std::string> messages() const;

 private:
  struct Origin {
    std::string path;
    std::string text;
    std::size_t order;
  };
  struct Entry {
    bool from_set;
    std::size_t set_order;
    int line;
    int column;
    std::string text;
  };
  const Origin* origin_of(const std::string& path) const;
  std::string where(const YAML::Mark& mark, const std::string& path) const;
  void add(Entry entry);

  std::string source_;
  std::vector<Origin> origins_;
  std::vector<Entry> entries_;
  std::map<std::string, std::string, std::less<>> locations_;
};

// A key looked up in a mapping. Errors about its value are reported at the key's line.
struct Field {
  std::string path;
  YAML::Node node;      // meaningful only when present
  YAML::Mark key_mark;  // the key, or the enclosing mapping's key when absent
  bool present = false;
};

// One mapping, read key by key. An absent or null mapping reads as empty; anything else but
// a mapping is reported once.
class MapReader {
 public:
  MapReader(Diagnostics& diag, const Field& field);

  Diagnostics& diag() { return diag_; }
  bool ok() const { return ok_; }
  const std::string& path() const { return path_; }
  // Where the mapping's key is (for errors about the section as a whole).
  const YAML::Mark& mark() const { return mark_; }

  // Looks `key` up, marks it consumed, and adds it to the keys this section knows.
  Field take(std::string_view key);
  // "path.key: missing (reason)" at this mapping's key; silent if this is not a mapping.
  void missing(std::string_view key, const std::string& reason);
  // If `key` is present: "path.key: not used by <reason>" (it is consumed); an explicit null
  // value is accepted without a word.
  void not_used(std::string_view key, const std::string& reason);
  // Reports every key not consumed as unknown, suggesting from the keys taken so far.
  void finish();
  // Consumes whatever is left without a word: only after an error already reported makes
  // the rest of the section meaningless (e.g. an operator kind that does not exist).
  void skip_rest();

 private:
  struct Entry {
    std::string key;
    YAML::Mark mark;
    YAML::Node value;
    bool consumed;
  };
  Entry* find(std::string_view key);

  Diagnostics& diag_;
  std::unordered_map<std::string, std::size_t> index_;  // key -> entries_ position
  std::string path_;
  YAML::Mark mark_;
  std::vector<std::string> known_;  // keys taken, in reading order (for suggestions)
  std::vector<Entry> entries_;
  bool ok_ = true;
};

// "unknown key (did you mean 'x'?)" or "unknown key; expected one of: a, b, c".
std::string unknown_key_message(std::string_view key, const std::vector<std::string>& expected);

// Bounds on a real value and how they read in a message: "> 0", ">= 0", "in [0, 1)".
struct Range {
  enum class Bound { kNone, kOpen, kClosed };
  Bound lo_kind = Bound::kNone;
  double lo = 0.0;
  Bound hi_kind = Bound::kNone;
  double hi = 0.0;

  static Range any() { return {}; }
  static Range greater_than(double v) { return {Bound::kOpen, v, Bound::kNone, 0.0}; }
  static Range at_least(double v) { return {Bound::kClosed, v, Bound::kNone, 0.0}; }
  static Range interval(double lo_v, bool lo_closed, double hi_v, bool hi_closed) {
    return {lo_closed ? Bound::kClosed : Bound::kOpen, lo_v,
            hi_closed ? Bound::kClosed : Bound::kOpen, hi_v};
  }
  bool contains(double v) const;
  std::string describe() const;
};

// Bounds on an integer. With `open_top` the upper bound is only the storage limit and the
// range reads ">= lo"; otherwise it reads "in lo..hi".
struct IntRange {
  long long lo = std::numeric_limits<long long>::min();
  long long hi = std::numeric_limits<long long>::max();
  bool open_top = true;

  static IntRange at_least(long long v, long long storage_max) { return {v, storage_max, true}; }
  static IntRange between(long long lo_v, long long hi_v) { return {lo_v, hi_v, false}; }
};

// Each reader returns nothing when the key is absent (no message) or its value is wrong (one
// message, echoing the value's text).
std::optional<double> read_number(Diagnostics& diag, const Field& field,
                                  const Range& range = Range::any());
std::optional<long long> read_integer(Diagnostics& diag, const Field& field, const IntRange& range);
std::optional<bool> read_bool(Diagnostics& diag, const Field& field);
std::optional<std::string> read_string(Diagnostics& diag, const Field& field);
// Index into `choices` of the value: "must be one of a, b; got 'c'".
std::optional<std::size_t> read_choice(Diagnostics& diag, const Field& field,
                                       const std::vector<std::string>& choices);
// A non-empty list of finite numbers, each in `range`; a bad element is reported as
// "path[i]: ...".
std::optional<std::vector<double>> read_number_list(Diagnostics& diag, const Field& field,
                                                    const Range& range = Range::any());
// An unsigned integer written in decimal or 0x hexadecimal, at most `max` (ids, usages, masks:
// the numbers datasheets and descriptors print in hexadecimal).
std::optional<std::uint32_t> read_hex(Diagnostics& diag, const Field& field, std::uint32_t max);

// The readers above into a setting: `out` takes the value when the key is present and valid and
// keeps its default otherwise (a wrong value has its message in the map's Diagnostics).
void number(MapReader& map, const Field& field, const Range& range, double& out);
inline void number(MapReader& map, std::string_view key, const Range& range, double& out) {
  number(map, map.take(key), range, out);
}
template <typename T>
void integer(MapReader& map, const Field& field, const IntRange& range, T& out) {
  if (const auto v = read_integer(map.diag(), field, range)) out = static_cast<T>(*v);
}
template <typename T>
void integer(MapReader& map, std::string_view key, const IntRange& range, T& out) {
  integer(map, map.take(key), range, out);
}

}  // namespace hapticd::config::schema
