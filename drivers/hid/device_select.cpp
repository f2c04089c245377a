#include "drivers/hid/device_select.h"

#include "base/hex.h"

namespace hapticd::drivers::hid {
namespace {

// USB ids and usages in lower case, as lsusb and the kernel show them.
std::string hex4(std::uint16_t v) { return base::hex(v, 4, base::HexCase::kLower); }

std::string one_line(const DeviceListing& d) {
  std::string s = hex4(d.vendor_id).substr(2) + ":" + hex4(d.product_id).substr(2);
  if (!d.product.empty()) s += " '" + d.product + "'";
  if (!d.manufacturer.empty()) s += " by '" + d.manufacturer + "'";
  if (!d.serial.empty()) s += ", serial '" + d.serial + "'";
  if (d.interface >= 0) s += ", interface " + std::to_string(d.interface);
  s += ", usage " + hex4(d.usage_page) + ":" + hex4(d.usage) + " at " + d.path;
  return s;
}

}  // namespace

std::string to_utf8(const wchar_t* w) {
  std::string s;
  for (; w != nullptr && *w != 0; ++w) {
    const auto c = static_cast<std::uint32_t>(*w);
    if (c < 0x80) {
      s += static_cast<char>(c);
    } else if (c < 0x800) {
      s += static_cast<char>(0xC0 | (c >> 6));
      s += static_cast<char>(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
      s += static_cast<char>(0xE0 | (c >> 12));
      s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (c & 0x3F));
    } else {
      s += static_cast<char>(0xF0 | (c >> 18));
      s += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
      s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (c & 0x3F));
    }
  }
  return s;
}

std::vector<DeviceListing> matching(const Selector& s, const std::vector<DeviceListing>& all) {
  std::vector<DeviceListing> out;
  for (const DeviceListing& d : all) {
    if (!s.path.empty()) {
      if (d.path == s.path) out.push_back(d);
      continue;
    }
    if (s.vendor_id && d.vendor_id != *s.vendor_id) continue;
    if (s.product_id && d.product_id != *s.product_id) continue;
    if (!s.serial.empty() && d.serial != s.serial) continue;
    if (s.interface && d.interface != *s.interface) continue;
    if (s.usage_page && d.usage_page != *s.usage_page) continue;
    if (s.usage && d.usage != *s.usage) continue;
    // hidapi lists a device once per top-level collection on some backends: one path is one
    // device to open.
    bool seen = false;
    for (const DeviceListing& o : out) seen = seen || o.path == d.path;
    if (!seen) out.push_back(d);
  }
  return out;
}

std::string describe(const Selector& s) {
  if (!s.path.empty()) return "path '" + s.path + "'";
  std::string t;
  const auto add = [&](const std::string& part) { t += (t.empty() ? "" : ", ") + part; };
  if (s.vendor_id) add("vendor_id " + hex4(*s.vendor_id));
  if (s.product_id) add("product_id " + hex4(*s.product_id));
  if (!s.serial.empty()) add("serial '" + s.serial + "'");
  if (s.interface) add("interface " + std::to_string(*s.interface));
  if (s.usage_page) add("usage_page " + hex4(*s.usage_page));
  if (s.usage) add("usage " + hex4(*s.usage));
  return t.empty() ? "any device" : t;
}

Selection select_one(const Selector& s, const std::vector<DeviceListing>& all,
                     const char* backend) {
  const std::vector<DeviceListing> found = matching(s, all);
  if (found.size() == 1) return {found.front(), ""};
  std::string e;
  if (found.empty()) {
    e = "no HID device matches device.hid.select (" + describe(s) + ") through the " + backend +
        " backend";
    if (all.empty()) {
      e += "; none is attached (or none is accessible: see `hapticd udev-rules`)";
    } else {
      e += "; attached:";
      for (const DeviceListing& d : all) e += "\n  " + one_line(d);
    }
  } else {
    e = std::to_string(found.size()) + " HID devices match device.hid.select (" + describe(s) +
        "); add serial, interface or path to choose one:";
    for (const DeviceListing& d : found) e += "\n  " + one_line(d);
  }
  return {std::nullopt, e};
}

std::string format_listing(const std::vector<DeviceListing>& all, const char* backend) {
  std::string out;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const DeviceListing& d = all[i];
    // hidapi lists a device once per top-level collection (a PID device: six or more): one
    // entry per path, naming every usage.
    bool seen = false;
    std::string more;
    for (std::size_t j = 0; j < all.size(); ++j) {
      if (all[j].path != d.path) continue;
      seen = seen || j < i;
      if (j > i) more += ", " + hex4(all[j].usage_page) + ":" + hex4(all[j].usage);
    }
    if (seen) continue;
    Selector s;
    s.vendor_id = d.vendor_id;
    s.product_id = d.product_id;
    // Add what tells this one apart from its twins, in the order a person would reach for.
    if (matching(s, all).size() > 1 && !d.serial.empty()) s.serial = d.serial;
    if (matching(s, all).size() > 1 && d.interface >= 0) s.interface = d.interface;
    if (matching(s, all).size() > 1) s.usage_page = d.usage_page;
    std::string sel = "{vendor_id: " + hex4(d.vendor_id) + ", product_id: " + hex4(d.product_id);
    if (!s.serial.empty()) sel += ", serial: \"" + d.serial + "\"";
    if (s.interface) sel += ", interface: " + std::to_string(d.interface);
    if (s.usage_page) sel += ", usage_page: " + hex4(d.usage_page);
    if (matching(s, all).size() > 1) sel = "{path: \"" + d.path + "\"";
    sel += "}";
    std::string line = one_line(d);
    if (!more.empty()) line.insert(line.rfind(" at " + d.path), more);
    out += "  " + line + (d.bus.empty() ? "" : " (" + d.bus + ")") + "\n";
    out += "    device.hid: {backend: " + std::string(backend) + ", select: " + sel + "}\n";
  }
  if (out.empty()) out = "  (none)\n";
  return out;
}

}  // namespace hapticd::drivers::hid
