#include "service/commands/udev_rules.h"

#include <filesystem>
#include <sstream>

#include "base/hex.h"
#include "config/config_loader.h"
#include "service/exit_codes.h"
#include "service/result_output.h"
#if HAPTICD_WITH_CAN
#include "drivers/can/can_settings.h"
#endif
#if HAPTICD_WITH_GPIO
#include "drivers/gpio/gpio_settings.h"
#endif
#if HAPTICD_WITH_HID
#include "drivers/hid/hid_settings.h"
#endif
#if HAPTICD_WITH_EVDEV
#include "drivers/evdev/evdev_settings.h"
#endif

namespace hapticd::service {
namespace {

// A value put into a rule must be matched literally: no udev pattern (* ? [ ] |), no quote,
// no substitution (% $), no space.
bool literal(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.' || c == ':';
    if (!ok) return false;
  }
  return true;
}

[[maybe_unused]] void require_literal(const config::Config& cfg, const std::string& key,
                                      const std::string& value) {
  if (literal(value)) return;
  throw config::ConfigError({cfg.locate(key) + ": " + key + ": '" + value +
                             "' cannot go into a udev rule as it is (only letters, digits and "
                             "_ - . : are matched literally); write that rule by hand"});
}

// A USB id as sysfs writes it and udev matches it: four lower-case digits, no 0x.
[[maybe_unused]] std::string hex4(unsigned v) {
  return base::hex(v & 0xFFFFu, 4, base::HexCase::kLower).substr(2);
}

[[maybe_unused]] std::string group_mode() {
  return std::string(", GROUP=\"") + kServiceGroup + "\", MODE=\"0660\"";
}

// `text` as comment lines of at most 99 columns.
void comment(std::ostream& out, const std::string& text) {
  std::istringstream words(text);
  std::string line;
  for (std::string word; words >> word;) {
    if (!line.empty() && line.size() + 1 + word.size() > 97) {
      out << "# " << line << "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out << "# " << line << "\n";
}

#if HAPTICD_WITH_CAN
void can_rules(const config::Config& cfg, std::ostream& out) {
  const auto& s = drivers::can::can_settings(cfg);
  require_literal(cfg, "device.can.interface", s.interface);
  if (s.interface.rfind("vcan", 0) == 0 || s.interface.rfind("vxcan", 0) == 0) {
    comment(out, "device.can.interface " + s.interface +
                     " is a virtual bus: it has no bitrate, and udev has nothing to set.");
    return;
  }
  const std::string rate = std::to_string(s.bitrate);
  comment(out, "device.can: " + s.interface + ", and no other interface, at " + rate +
                   " bit/s (device.can.bitrate) with restart-ms 100 (the controller recovers "
                   "from bus-off by itself; hapticd still faults on it), brought up as it "
                   "appears.");
  out << "ACTION==\"add\", SUBSYSTEM==\"net\", KERNEL==\""
      << s.interface << "\", ATTR{type}==\"280\", RUN+=\"/sbin/ip link set "
      << s.interface << " type can bitrate " << rate
      << " restart-ms 100\", RUN+=\"/sbin/ip link set " << s.interface << " up\"\n";
}
#endif

#if HAPTICD_WITH_GPIO
std::string chip_kernel_name(const config::Config& cfg, const std::string& chip) {
  const std::string name = chip.rfind("/dev/", 0) == 0 ? chip.substr(5) : chip;
  const bool numbered = name.size() > 8 && name.rfind("gpiochip", 0) == 0 &&
                        name.find_first_not_of("0123456789", 8) == std::string::npos;
  if (numbered) return name;
  throw config::ConfigError(
      {cfg.locate("device.gpio.chip") + ": device.gpio.chip: '" + chip +
       "' is not a chip's kernel name, and udev matches a GPIO chip by that name only: give it "
       "as gpiochipN (the `gpiodetect` line that shows this label)"});
}

void gpio_rules(const config::Config& cfg, std::ostream& out) {
  const auto& s = drivers::gpio::gpio_settings(cfg);
  const std::string chip = chip_kernel_name(cfg, s.chip);
  std::string lines = std::to_string(s.line_a) + ", " + std::to_string(s.line_b) + ", " +
                      std::to_string(s.line_direction);
  if (s.line_index) lines += ", " + std::to_string(*s.line_index);
  if (s.line_fault) lines += ", " + std::to_string(*s.line_fault);
  comment(out, "device.gpio.chip: " + chip +
                   ". A GPIO chip is granted whole: whoever opens it may request any of its "
                   "lines no one holds. This instance uses lines " +
                   lines + " (docs/operations.md).");
  out << "SUBSYSTEM==\"gpio\", KERNEL==\"" << chip << "\"" << group_mode() << "\n";
  if (s.pwm_sysfs_root != "/sys/class/pwm") {
    comment(out, "device.gpio.pwm.sysfs_root is " + s.pwm_sysfs_root +
                     ", not /sys/class/pwm: udev has no PWM chip to set up there.");
    return;
  }
  const std::string pwmchip = "pwmchip" + std::to_string(s.pwm_chip);
  const std::string ch = "pwm" + std::to_string(s.pwm_channel);
  const std::string files = "period duty_cycle polarity enable";
  comment(out, "device.gpio.pwm: channel " + std::to_string(s.pwm_channel) + " of " + pwmchip +
                   ", exported by udev as root; the group gets its period, duty_cycle, "
                   "polarity and enable. The chip's export and unexport stay root's: no other "
                   "channel can be taken or released.");
  out << "ACTION==\"add|change\", SUBSYSTEM==\"pwm\", KERNEL==\"" << pwmchip
      << "\", ENV{UNEXPORT}==\"\", RUN+=\"/bin/sh -c 'test -d %S%p/" << ch << " || echo "
      << s.pwm_channel << " >%S%p/export; cd %S%p/" << ch << " && chgrp " << kServiceGroup << " "
      << files << " && chmod g+w " << files << "'\"\n";
}
#endif

#if HAPTICD_WITH_HID
void hid_rules(const config::Config& cfg, std::ostream& out) {
  const auto* s = dynamic_cast<const drivers::hid::HidSettings*>(cfg.device.settings.get());
  if (s == nullptr) return;
  const auto& sel = s->select;
  const bool libusb = s->backend == drivers::hid::Backend::kLibusb;
  const std::string node = libusb ? "the USB device node" : "the hidraw node";
  const std::string head =
      libusb ? "SUBSYSTEM==\"usb\", ENV{DEVTYPE}==\"usb_device\", " : "SUBSYSTEM==\"hidraw\", ";
  if (!sel.path.empty()) {
    // hidapi's path: /dev/hidrawN (hidraw), BUS-PORTS:CONFIG.INTERFACE (libusb).
    std::string name = sel.path.rfind("/dev/", 0) == 0 ? sel.path.substr(5) : sel.path;
    if (libusb) name = name.substr(0, name.find(':'));
    require_literal(cfg, "device.hid.select.path", name);
    comment(out, "device.hid.select.path: " + node + " " + name + ", whatever is plugged there.");
    out << head << "KERNEL==\"" << name << "\"" << group_mode() << "\n";
    return;
  }
  if (!sel.vendor_id || !sel.product_id) {
    throw config::ConfigError(
        {cfg.locate("device.hid.select") +
         ": device.hid.select: udev can give the group exactly this device only by its vendor "
         "and product id (or its path): set vendor_id and product_id"});
  }
  if (!sel.serial.empty()) require_literal(cfg, "device.hid.select.serial", sel.serial);
  const std::string vid = hex4(*sel.vendor_id), pid = hex4(*sel.product_id);
  comment(out, "device.hid.select: " + node + " of USB device " + vid + ":" + pid +
                   (sel.serial.empty() ? "" : ", serial " + sel.serial) +
                   " (every HID interface of it), and of no other device.");
  const char* attr = libusb ? "ATTR" : "ATTRS";  // a hidraw node's USB device is a parent
  out << head << attr << "{idVendor}==\"" << vid << "\", " << attr << "{idProduct}==\"" << pid
      << "\"";
  if (!sel.serial.empty()) out << ", " << attr << "{serial}==\"" << sel.serial << "\"";
  out << group_mode() << "\n";
}
#endif

#if HAPTICD_WITH_EVDEV
// The input device's nodes (its eventN, and a joystick's jsN beside it), by its path, its ids
// (with its serial) or its name: never every input node (a keyboard's would let its reader
// log keystrokes).
void evdev_rules(const config::Config& cfg, std::ostream& out) {
  const auto& sel = drivers::evdev::evdev_settings(cfg).select;
  const std::string head = "SUBSYSTEM==\"input\", ";
  if (!sel.path.empty()) {
    const std::string name = sel.path.substr(std::string("/dev/").size());
    require_literal(cfg, "device.evdev.select.path", name.substr(name.rfind('/') + 1));
    comment(out,
            "device.evdev.select.path: the input node " + sel.path + ", whatever device it is.");
    const bool link = name.rfind("input/event", 0) != 0;
    out << head << (link ? "SYMLINK==\"" : "KERNEL==\"")
        << (link ? name : name.substr(name.rfind('/') + 1)) << "\"" << group_mode() << "\n";
    return;
  }
  if (sel.vendor_id && sel.product_id) {
    if (!sel.uniq.empty()) require_literal(cfg, "device.evdev.select.uniq", sel.uniq);
    const std::string vid = hex4(*sel.vendor_id), pid = hex4(*sel.product_id);
    comment(out, "device.evdev.select: the input nodes of device " + vid + ":" + pid +
                     (sel.uniq.empty() ? "" : ", uniq " + sel.uniq) + ", and of no other device.");
    out << head << "ATTRS{id/vendor}==\"" << vid << "\", ATTRS{id/product}==\"" << pid << "\"";
    if (!sel.uniq.empty()) out << ", ATTRS{uniq}==\"" << sel.uniq << "\"";
    out << group_mode() << "\n";
    return;
  }
  if (sel.name.empty()) {
    throw config::ConfigError(
        {cfg.locate("device.evdev.select") +
         ": device.evdev.select: udev can give the group exactly this device only by its vendor "
         "and product id, its name or its path: set one of them"});
  }
  require_literal(cfg, "device.evdev.select.name", sel.name);
  comment(out, "device.evdev.select.name: the input nodes of the device named " + sel.name + ".");
  out << head << "ATTRS{name}==\"" << sel.name << "\"" << group_mode() << "\n";
}
#endif

}  // namespace

std::string instance_udev_rules(const config::Config& cfg, const std::string& instance) {
  std::ostringstream out;
  comment(out, "udev rules of hapticd instance " + instance +
                   ", written by `hapticd udev-rules` from " + cfg.source_name +
                   ". Install as /etc/udev/rules.d/70-hapticd-" + instance +
                   ".rules, then `udevadm control --reload` and `udevadm trigger --action=add` "
                   "(docs/operations.md). When the configuration changes, write them again "
                   "rather than edit them.");
  const std::string& d = cfg.device.driver;
#if HAPTICD_WITH_CAN
  if (d == "can") can_rules(cfg, out);
#endif
#if HAPTICD_WITH_GPIO
  if (d == "gpio") gpio_rules(cfg, out);
#endif
#if HAPTICD_WITH_HID
  if (d == "hid") hid_rules(cfg, out);
#endif
#if HAPTICD_WITH_EVDEV
  if (d == "evdev") evdev_rules(cfg, out);
#endif
  if (d == "sim") comment(out, "device.driver sim: no device, nothing for udev to do.");
  return out.str();
}

int udev_rules_command(const ConfigOptions& options, std::string instance) {
  const config::Config cfg = load_config(options);
  if (instance.empty()) {
    instance =
        options.path.empty() ? "hapticd" : std::filesystem::path(options.path).stem().string();
  }
  if (!literal(instance)) {
    throw config::ConfigError(
        {"--instance: '" + instance + "' is not a plain instance name (letters, digits, _ - . :)"});
  }
  return write_stdout(instance_udev_rules(cfg, instance)) ? kExitOk : kExitRuntimeFault;
}

}  // namespace hapticd::service
