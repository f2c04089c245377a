// `hapticd udev-rules`: the udev rules one instance needs, written from its configuration, so
// that installing hapticd changes nothing on the host by itself and an instance touches only
// what its configuration names: the bitrate of its CAN interface (never another bus), its
// GPIO chip and its one PWM channel, its HID device's hidraw (or USB) node by vendor and
// product id. The administrator writes them where udev reads them
// (/etc/udev/rules.d/70-hapticd-NAME.rules) and can read what each does before it does it
// (docs/operations.md). Not RT code.
#pragma once

#include <string>

#include "config/config.h"
#include "service/config_source.h"

namespace hapticd::service {

inline constexpr const char* kServiceGroup = "hapticd";

// The rules file's text for instance `instance` (a systemd instance name, for the comments
// and the file name they suggest). Throws config::ConfigError naming the key when the
// configuration selects its device in a way a udev rule cannot match exactly (a GPIO chip
// given by label, a HID device without vendor and product id, characters udev would read as a
// pattern).
std::string instance_udev_rules(const config::Config& cfg, const std::string& instance);

// Prints instance_udev_rules() of the configuration for `instance`; empty: the configuration
// file's name without .yaml (hapticd@NAME reads /etc/hapticd/NAME.yaml), "hapticd" for the
// embedded one. Exit 0, 2 bad configuration, 1 when standard output cannot be written.
int udev_rules_command(const ConfigOptions& options, std::string instance);

}  // namespace hapticd::service
