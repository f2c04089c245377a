#include "config/config_loader.h"
#include "drivers/hid/hid_driver.h"
#include "drivers/hid/hid_settings.h"

namespace hapticd::drivers::hid {

// The hidraw (or, over libusb, the USB device) node of the selected device, by its path or
// its vendor and product id (and serial): never every HID device.
void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const auto* s = dynamic_cast<const HidSettings*>(cfg.device.settings.get());
  if (s == nullptr) return;
  const auto& sel = s->select;
  const bool libusb = s->backend == Backend::kLibusb;
  const std::string node = libusb ? "the USB device node" : "the hidraw node";
  const std::string head =
      libusb ? "SUBSYSTEM==\"usb\", ENV{DEVTYPE}==\"usb_device\", " : "SUBSYSTEM==\"hidraw\", ";
  if (!sel.path.empty()) {
    // hidapi's path: /dev/hidrawN (hidraw), BUS-PORTS:CONFIG.INTERFACE (libusb).
    std::string name = sel.path.rfind("/dev/", 0) == 0 ? sel.path.substr(5) : sel.path;
    if (libusb) name = name.substr(0, name.find(':'));
    out.literal("device.hid.select.path", name);
    out.comment("device.hid.select.path: " + node + " " + name + ", whatever is plugged there.");
    out.rule(head + "KERNEL==\"" + name + "\"" + out.grant());
    return;
  }
  if (!sel.vendor_id || !sel.product_id) {
    throw config::ConfigError(
        {cfg.locate("device.hid.select") +
         ": device.hid.select: udev can give the group exactly this device only by its vendor "
         "and product id (or its path): set vendor_id and product_id"});
  }
  if (!sel.serial.empty()) out.literal("device.hid.select.serial", sel.serial);
  const std::string vid = usb_id(*sel.vendor_id), pid = usb_id(*sel.product_id);
  out.comment("device.hid.select: " + node + " of USB device " + vid + ":" + pid +
              (sel.serial.empty() ? "" : ", serial " + sel.serial) +
              " (every HID interface of it), and of no other device.");
  const std::string attr = libusb ? "ATTR" : "ATTRS";  // a hidraw node's USB device is a parent
  std::string rule =
      head + attr + "{idVendor}==\"" + vid + "\", " + attr + "{idProduct}==\"" + pid + "\"";
  if (!sel.serial.empty()) rule += ", " + attr + "{serial}==\"" + sel.serial + "\"";
  out.rule(rule + out.grant());
}

}  // namespace hapticd::drivers::hid
