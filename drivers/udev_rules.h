// What a driver writes into `hapticd udev-rules` (drivers/device_entry.h, udev_rules): the
// rules an instance needs for its device and nothing else, each explained by a comment, so an
// administrator can read what a rule does before udev does it (docs/operations.md). Not RT code.
#pragma once

#include <sstream>
#include <string>
#include <utility>

#include "config/config.h"

namespace hapticd::drivers {

class UdevRules {
 public:
  // `group`: the group the rules grant the device to (the service's).
  UdevRules(const config::Config& cfg, std::string group) : cfg_(cfg), group_(std::move(group)) {}

  // `text` as comment lines of at most 99 columns.
  void comment(const std::string& text);
  // One rule, as given (one line).
  void rule(const std::string& line) { out_ << line << "\n"; }

  // `value` of `key`, which goes into a rule: it must be matched literally (no udev pattern,
  // quote, substitution or space). Throws config::ConfigError naming the key otherwise.
  void literal(const std::string& key, const std::string& value) const;
  // `, GROUP="<group>", MODE="0660"`: what ends a rule that grants a node.
  std::string grant() const;
  const std::string& group() const { return group_; }

  std::string text() const { return out_.str(); }

 private:
  const config::Config& cfg_;
  std::string group_;
  std::ostringstream out_;
};

// Whether udev matches `s` literally: letters, digits and _ - . : only, not empty.
bool udev_literal(const std::string& s);
// A USB id as sysfs writes it and udev matches it: four lower-case digits, no 0x.
std::string usb_id(unsigned v);

}  // namespace hapticd::drivers
