// Entry points: read the text, parse it, merge the --set overrides into the tree, validate it
// against the schema, and record the merged document as Config::effective_yaml.
#include "config/config_loader.h"

#include <yaml-cpp/yaml.h>

#include <string>
#include <utility>

#include "config/config_schema.h"
#include "config/schema_reader.h"
#include "config/yaml_documents.h"

namespace hapticd::config {
namespace {

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i) out += '\n';
    out += lines[i];
  }
  return out;
}

// "a.b.c" -> {a, b, c}; empty when any segment is empty.
std::vector<std::string> split_key_path(std::string_view path) {
  std::vector<std::string> segments;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    const std::string_view seg =
        path.substr(start, dot == std::string_view::npos ? std::string_view::npos : dot - start);
    if (seg.empty()) return {};
    segments.emplace_back(seg);
    if (dot == std::string_view::npos) return segments;
    start = dot + 1;
  }
}

// "walls[2]" -> {"walls", 2}: an element of a list; any other segment -> {it, npos}.
std::pair<std::string, std::size_t> indexed(const std::string& segment) {
  const std::size_t open = segment.find('[');
  if (open == 0 || open == std::string::npos || segment.back() != ']') {
    return {segment, std::string::npos};
  }
  const std::string digits = segment.substr(open + 1, segment.size() - open - 2);
  if (digits.empty() || digits.size() > 4 ||
      digits.find_first_not_of("0123456789") != std::string::npos) {
    return {segment, std::string::npos};
  }
  return {segment.substr(0, open), std::stoul(digits)};
}

std::string override_text(const Override& o) {
  return o.text.empty() ? o.key_path + "=" + o.value : o.text;
}

// Writes each --set into the tree, creating missing intermediate mappings, and tells `diag`
// which paths came from which argument (their yaml-cpp marks point into the value string).
void apply_overrides(YAML::Node& root, const std::vector<Override>& overrides,
                     schema::Diagnostics& diag) {
  for (std::size_t i = 0; i < overrides.size(); ++i) {
    const Override& o = overrides[i];
    const std::string text = override_text(o);
    const std::vector<std::string> segments = split_key_path(o.key_path);
    if (segments.empty()) {
      diag.set_error(text, i, "", "expected key.path=value");
      continue;
    }
    YAML::Node value;
    try {
      const std::vector<YAML::Node> docs = load_yaml_documents(o.value);
      if (docs.size() > 1) {
        diag.set_error(text, i, o.key_path, "value holds more than one YAML document ('---')");
        continue;
      }
      if (!docs.empty()) value = docs.front();
    } catch (const YAML::Exception& e) {
      diag.set_error(text, i, o.key_path, "value is not valid YAML: " + e.msg);
      continue;
    }
    // Walking down must rebind the handle with reset(): assigning one yaml-cpp Node to
    // another overwrites the node it refers to, which would rewrite the document.
    YAML::Node cur(root);
    std::string path;
    std::string created;  // the outermost mapping this --set had to create
    bool blocked = false;
    for (std::size_t s = 0; s + 1 < segments.size(); ++s) {
      path = schema::child_path(path, segments[s]);
      if (const auto [key, index] = indexed(segments[s]); index != std::string::npos) {
        // An element of a list the document has: walls[1].stiffness.
        const YAML::Node list = cur[key];
        if (!list.IsSequence() || index >= list.size() || !list[index].IsMap()) {
          diag.set_error(
              text, i, path,
              "no such mapping to set '" + o.key_path.substr(path.size() + 1) + "' inside");
          blocked = true;
          break;
        }
        cur.reset(list[index]);
        continue;
      }
      YAML::Node next = cur[segments[s]];
      if (!next.IsDefined() || next.IsNull()) {
        if (!next.IsDefined() && created.empty()) created = path;
        next = YAML::Node(YAML::NodeType::Map);
      } else if (!next.IsMap()) {
        diag.set_error(text, i, path,
                       "cannot set '" + o.key_path.substr(path.size() + 1) +
                           "' inside it: it is not a mapping");
        blocked = true;
        break;
      }
      cur.reset(next);
    }
    if (blocked) continue;
    if (const auto [key, index] = indexed(segments.back()); index != std::string::npos) {
      YAML::Node list = cur[key];
      if (!list.IsSequence() || index >= list.size()) {
        diag.set_error(text, i, o.key_path, "no such element of a list to set");
        continue;
      }
      list[index] = value;
    } else {
      cur[segments.back()] = value;
    }
    diag.set_origin(created.empty() ? o.key_path : created, text, i);
  }
}

std::string emit(const YAML::Node& root) {
  YAML::Emitter out;
  out << root;
  std::string text = out.c_str();
  text += '\n';
  return text;
}

}  // namespace

std::string Config::locate(std::string_view key_path) const {
  for (std::string_view p = key_path; !p.empty();) {
    if (const auto it = key_locations.find(p); it != key_locations.end()) return it->second;
    const std::size_t dot = p.rfind('.');
    p = dot == std::string_view::npos ? std::string_view() : p.substr(0, dot);
  }
  return source_name;
}

ConfigError::ConfigError(std::vector<std::string> messages)
    : std::runtime_error(join_lines(messages)), messages_(std::move(messages)) {}

Override parse_override(std::string_view arg) {
  const std::size_t eq = arg.find('=');
  if (eq == std::string_view::npos || split_key_path(arg.substr(0, eq)).empty()) {
    throw ConfigError({"--set " + std::string(arg) + ": expected key.path=value"});
  }
  return {std::string(arg.substr(0, eq)), std::string(arg.substr(eq + 1)), std::string(arg)};
}

const DriverSchemas& sim_driver_only() {
  static const DriverSchemas kSim{{"sim", {}}};  // the plant section device.sim is the loader's
  return kSim;
}

Config load_config_text(std::string_view yaml, const std::string& source_name,
                        const std::vector<Override>& overrides, const std::string& base_dir,
                        const DriverSchemas& drivers) {
  std::vector<YAML::Node> documents;
  try {
    documents = load_yaml_documents(std::string(yaml));
  } catch (const YAML::Exception& e) {
    std::string where = source_name;
    if (e.mark.line >= 0) {
      where += ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1);
    }
    throw ConfigError({schema::printable(where + ": YAML syntax error: " + e.msg)});
  }
  if (documents.size() > 1) {
    // Reading only the first would silently ignore whatever the second one sets.
    const YAML::Mark m = documents[1].Mark();
    throw ConfigError({schema::printable(
        source_name + (m.line >= 0 ? ":" + std::to_string(m.line + 1) : std::string()) +
        ": a second YAML document ('---') follows the first; a configuration is one document")});
  }
  YAML::Node root = documents.empty() ? YAML::Node() : documents.front();
  // An empty document (or one that is all comments) is a configuration of defaults.
  if (root.IsNull()) root.reset(YAML::Node(YAML::NodeType::Map));

  schema::Diagnostics diag(source_name);
  if (root.IsMap()) apply_overrides(root, overrides, diag);
  Config config;
  schema::read_config(diag, root, base_dir, drivers, config);
  if (!diag.empty()) throw ConfigError(diag.messages());

  if (config.device.sim.op.kind == OperatorSpec::Kind::kReplay) {
    // The effective document travels inside tick logs; an absolute path keeps it meaningful
    // when it is loaded again from somewhere else.
    YAML::Node op = root["device"]["sim"]["operator"];
    op["log"] = config.device.sim.op.replay_log;
  }
  config.source_name = source_name;
  config.effective_yaml = emit(root);
  config.key_locations = diag.locations();
  return config;
}

std::string with_setting(std::string_view effective_yaml, const Override& o) {
  const std::vector<YAML::Node> documents = load_yaml_documents(std::string(effective_yaml));
  YAML::Node root = documents.empty() ? YAML::Node(YAML::NodeType::Map) : documents.front();
  schema::Diagnostics diag("effective configuration");
  apply_overrides(root, {o}, diag);
  if (!diag.empty()) throw ConfigError(diag.messages());
  return emit(root);
}

Config load_embedded_default(const std::vector<Override>& overrides, const DriverSchemas& drivers) {
  return load_config_text(embedded_default_yaml(), "config/sim.yaml (embedded)", overrides, ".",
                          drivers);
}

}  // namespace hapticd::config
