#include "drivers/udev_rules.h"

#include "base/hex.h"
#include "config/config_loader.h"

namespace hapticd::drivers {

bool udev_literal(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.' || c == ':';
    if (!ok) return false;
  }
  return true;
}

std::string usb_id(unsigned v) {
  return base::hex(v & 0xFFFFu, 4, base::HexCase::kLower).substr(2);
}

void UdevRules::comment(const std::string& text) {
  std::istringstream words(text);
  std::string line;
  for (std::string word; words >> word;) {
    if (!line.empty() && line.size() + 1 + word.size() > 97) {
      out_ << "# " << line << "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out_ << "# " << line << "\n";
}

void UdevRules::literal(const std::string& key, const std::string& value) const {
  if (udev_literal(value)) return;
  throw config::ConfigError({cfg_.locate(key) + ": " + key + ": '" + value +
                             "' cannot go into a udev rule as it is (only letters, digits and "
                             "_ - . : are matched literally); write that rule by hand"});
}

std::string UdevRules::grant() const { return ", GROUP=\"" + group_ + "\", MODE=\"0660\""; }

}  // namespace hapticd::drivers
