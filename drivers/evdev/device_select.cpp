#include "drivers/evdev/device_select.h"

#include <algorithm>
#include <array>
#include <string_view>

#include <yaml-cpp/yaml.h>

#include "base/hex.h"
#include "config/schema_reader.h"

namespace hapticd::drivers::evdev {
namespace {

using config::schema::printable;

std::string hex4(unsigned v) { return base::hex(v & 0xFFFFu, 4, base::HexCase::kLower); }

bool matches(const Selector& s, const InputListing& d) {
  return (s.name.empty() || s.name == d.name) && (!s.vendor_id || *s.vendor_id == d.vendor_id) &&
         (!s.product_id || *s.product_id == d.product_id) && (s.phys.empty() || s.phys == d.phys) &&
         (s.uniq.empty() || s.uniq == d.uniq);
}

// The select: mapping that picks `d` out of `all`: name and ids, then uniq or phys if needed,
// else the node's path. Written by yaml-cpp: a device names itself, and a name with a quote, a
// backslash or a control character must still paste as the YAML that selects it.
std::string select_keys(const InputListing& d, const std::vector<InputListing>& all) {
  Selector s;
  s.name = d.name;
  s.vendor_id = d.vendor_id;
  s.product_id = d.product_id;
  if (matching(s, "", all).size() > 1 && !d.uniq.empty()) s.uniq = d.uniq;
  if (matching(s, "", all).size() > 1 && !d.phys.empty()) s.phys = d.phys;
  YAML::Emitter out;
  out << YAML::Flow << YAML::BeginMap;
  const auto text = [&out](const char* key, const std::string& value) {
    out << YAML::Key << key << YAML::Value << YAML::DoubleQuoted << value;
  };
  if (matching(s, "", all).size() > 1) {
    text("path", d.links.empty() ? d.path : d.links.front());
  } else {
    text("name", d.name);
    out << YAML::Key << "vendor_id" << YAML::Value << hex4(d.vendor_id);
    out << YAML::Key << "product_id" << YAML::Value << hex4(d.product_id);
    if (!s.uniq.empty()) text("uniq", s.uniq);
    if (!s.phys.empty()) text("phys", s.phys);
  }
  out << YAML::EndMap;
  return out.c_str();
}

std::string axes_text(const InputListing& d) {
  std::string text;
  for (int code : d.abs_axes) text += (text.empty() ? "" : " ") + abs_name(code);
  return text.empty() ? "none" : text;
}

}  // namespace

std::optional<FfDriver> guess_ff_driver(const InputListing& d) {
  if (d.virtual_device) return FfDriver::kUinput;
  // hid-generic binds hid-pidff to a USB device with a complete PID descriptor (6.12 adds
  // hid-universal-pidff for the same protocol); the others play through ff-memless.
  static constexpr std::array<std::string_view, 2> kPid{"hid-generic", "hid-universal-pidff"};
  static constexpr std::array<std::string_view, 12> kMemless{
      "logitech", "thrustmaster", "xpad", "sony",  "dragonrise", "greenasia",
      "zeroplus", "pantherlord",  "gaff", "betop", "microsoft",  "hid-steam"};
  const auto known = [&](const auto& names) {
    return std::find(names.begin(), names.end(), d.kernel_driver) != names.end();
  };
  if (known(kPid)) return FfDriver::kPidff;
  if (known(kMemless)) return FfDriver::kMemless;
  return std::nullopt;
}

std::vector<InputListing> matching(const Selector& s, const std::string& resolved_path,
                                   const std::vector<InputListing>& all) {
  std::vector<InputListing> out;
  for (const InputListing& d : all) {
    const bool hit = s.path.empty()
                         ? matches(s, d)
                         : d.path == resolved_path || d.path == s.path ||
                               std::find(d.links.begin(), d.links.end(), s.path) != d.links.end();
    if (hit) out.push_back(d);
  }
  return out;
}

std::string describe(const Selector& s) {
  if (!s.path.empty()) return "path " + s.path;
  std::string text;
  const auto add = [&text](const std::string& part) { text += (text.empty() ? "" : ", ") + part; };
  if (!s.name.empty()) add("name '" + s.name + "'");
  if (s.vendor_id) add("vendor_id " + hex4(*s.vendor_id));
  if (s.product_id) add("product_id " + hex4(*s.product_id));
  if (!s.phys.empty()) add("phys '" + s.phys + "'");
  if (!s.uniq.empty()) add("uniq '" + s.uniq + "'");
  return text;
}

Selection select_one(const Selector& s, const std::string& resolved_path,
                     const std::vector<InputListing>& all) {
  const std::vector<InputListing> found = matching(s, resolved_path, all);
  if (found.size() == 1) return {found.front(), ""};
  std::string there;
  for (const InputListing& d : found.empty() ? all : found) {
    there += "\n  " + d.path + " \"" + printable(d.name) + "\" " + hex4(d.vendor_id) + ":" +
             hex4(d.product_id) + (d.phys.empty() ? "" : " phys " + printable(d.phys)) +
             (d.uniq.empty() ? "" : " uniq " + printable(d.uniq));
  }
  if (found.empty()) {
    return {std::nullopt,
            "no input device matches device.evdev.select (" + describe(s) + ")" +
                (all.empty() ? ": none is readable here" : "; attached and readable:" + there)};
  }
  return {std::nullopt, std::to_string(found.size()) +
                            " input devices match device.evdev.select (" + describe(s) +
                            "): add phys, uniq or path to tell them apart:" + there};
}

std::string format_listing(const std::vector<InputListing>& all, int unreadable) {
  std::string out = "evdev (input devices with FF_CONSTANT force feedback):\n";
  int others = 0;
  for (const InputListing& d : all) {
    if (!d.ff_constant) {
      ++others;
      continue;
    }
    const std::optional<FfDriver> ff = guess_ff_driver(d);
    out += "  " + d.path + "  \"" + printable(d.name) + "\"  " + hex4(d.vendor_id) + ":" +
           hex4(d.product_id) + (d.phys.empty() ? "" : "  phys " + printable(d.phys)) +
           (d.uniq.empty() ? "" : "  uniq " + printable(d.uniq)) + "\n";
    out += "    kernel driver " +
           (d.kernel_driver.empty() ? std::string("(none)") : d.kernel_driver) +
           (ff ? std::string(" (ff_driver: ") + to_string(*ff) + ")" : std::string()) +
           ", effects " + std::to_string(d.ff_effects) + (d.ff_gain ? ", FF_GAIN" : "") +
           (d.ff_autocenter ? ", FF_AUTOCENTER" : "") + "; axes " + axes_text(d) + "\n";
    for (const std::string& link : d.links) out += "    " + link + "\n";
    out += "    select: " + select_keys(d, all) + "\n";
  }
  if (out.find("select:") == std::string::npos) out += "  none\n";
  if (others > 0)
    out += "  (" + std::to_string(others) + " other input devices have no FF_CONSTANT)\n";
  if (unreadable > 0) {
    out += "  (" + std::to_string(unreadable) +
           " input devices could not be opened: permissions? `hapticd udev-rules` writes the "
           "rule for a configured one)\n";
  }
  return out;
}

}  // namespace hapticd::drivers::evdev
