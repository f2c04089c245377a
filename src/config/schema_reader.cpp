#include "config/schema_reader.h"

#include "config/config_loader.h"  // kMaxMessages

#include <algorithm>
#include <utility>

namespace hapticd::config::schema {
namespace {

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

}  // namespace

std::string quoted(const std::string& text) { return "'" + text + "'"; }

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

}  // namespace hapticd::config::schema
