#include "config/config_loader.h"
#include "drivers/evdev/evdev_driver.h"
#include "drivers/evdev/evdev_settings.h"

namespace hapticd::drivers::evdev {

// The input device's nodes (its eventN, and a joystick's jsN beside it), by its path, its ids
// (with its serial) or its name: never every input node (a keyboard's would let its reader
// log keystrokes).
void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const auto& sel = evdev_settings(cfg).select;
  const std::string head = "SUBSYSTEM==\"input\", ";
  if (!sel.path.empty()) {
    const std::string name = sel.path.substr(std::string("/dev/").size());
    out.literal("device.evdev.select.path", name.substr(name.rfind('/') + 1));
    out.comment("device.evdev.select.path: the input node " + sel.path +
                ", whatever device it is.");
    const bool link = name.rfind("input/event", 0) != 0;
    out.rule(head +
             (link ? "SYMLINK==\"" + name : "KERNEL==\"" + name.substr(name.rfind('/') + 1)) +
             "\"" + out.grant());
    return;
  }
  if (sel.vendor_id && sel.product_id) {
    if (!sel.uniq.empty()) out.literal("device.evdev.select.uniq", sel.uniq);
    const std::string vid = usb_id(*sel.vendor_id), pid = usb_id(*sel.product_id);
    out.comment("device.evdev.select: the input nodes of device " + vid + ":" + pid +
                (sel.uniq.empty() ? "" : ", uniq " + sel.uniq) + ", and of no other device.");
    std::string rule =
        head + "ATTRS{id/vendor}==\"" + vid + "\", ATTRS{id/product}==\"" + pid + "\"";
    if (!sel.uniq.empty()) rule += ", ATTRS{uniq}==\"" + sel.uniq + "\"";
    out.rule(rule + out.grant());
    return;
  }
  if (sel.name.empty()) {
    throw config::ConfigError(
        {cfg.locate("device.evdev.select") +
         ": device.evdev.select: udev can give the group exactly this device only by its vendor "
         "and product id, its name or its path: set one of them"});
  }
  out.literal("device.evdev.select.name", sel.name);
  out.comment("device.evdev.select.name: the input nodes of the device named " + sel.name + ".");
  out.rule(head + "ATTRS{name}==\"" + sel.name + "\"" + out.grant());
}

}  // namespace hapticd::drivers::evdev
