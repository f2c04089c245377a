#include "usb_acm_gadget.h"

#include <unistd.h>

#include "sysfs.h"

namespace hapticd::kernel_test {

UsbAcmGadget::UsbAcmGadget(UsbAcmGadgetConfig config)
    : config_(std::move(config)), root_(std::string(kUsbGadgets) + "/" + config_.name) {
  require_path(kUsbGadgets, "USB gadget configfs (libcomposite, configfs mounted)");
  const auto controllers = list_dir("/sys/class/udc");
  if (controllers.empty()) throw KernelFacilityError("no USB device controller (dummy_hcd)");
  try {
    create_configfs_tree();
    write_text(root_ + "/UDC", controllers.front());
    wait_until([&] { return !find_host_tty().empty(); }, std::chrono::seconds(20),
               "cdc_acm to bind gadget " + config_.name + " (modules cdc_acm, usb_f_acm)");
    host_path_ = "/dev/" + find_host_tty();
    device_path_ = "/dev/ttyGS" + read_text(root_ + "/functions/acm.usb0/port_num");
    wait_until([&] { return path_exists(host_path_) && path_exists(device_path_); },
               std::chrono::seconds(5), "the nodes " + host_path_ + " and " + device_path_);
  } catch (...) {
    remove_configfs_tree();
    throw;
  }
}

UsbAcmGadget::~UsbAcmGadget() { remove_configfs_tree(); }

void UsbAcmGadget::create_configfs_tree() {
  make_dir(root_);
  write_text(root_ + "/idVendor", "0x" + hex4(config_.vendor_id));
  write_text(root_ + "/idProduct", "0x" + hex4(config_.product_id));
  write_text(root_ + "/bcdUSB", "0x0200");
  make_dir(root_ + "/strings/0x409");
  write_text(root_ + "/strings/0x409/serialnumber", config_.serial);
  write_text(root_ + "/strings/0x409/manufacturer", config_.manufacturer);
  write_text(root_ + "/strings/0x409/product", config_.product);
  make_dir(root_ + "/configs/c.1");
  make_dir(root_ + "/configs/c.1/strings/0x409");
  write_text(root_ + "/configs/c.1/strings/0x409/configuration", "acm");
  make_dir(root_ + "/functions/acm.usb0");
  if (::symlink((root_ + "/functions/acm.usb0").c_str(),
                (root_ + "/configs/c.1/acm.usb0").c_str()) != 0) {
    throw_errno("link the ACM function into configuration c.1");
  }
}

// The host's tty of this gadget: a ttyACM whose USB device has our ids and serial.
std::string UsbAcmGadget::find_host_tty() const {
  for (const auto& tty : list_dir("/sys/class/tty")) {
    if (tty.rfind("ttyACM", 0) != 0) continue;
    // device -> the interface; its parent directory is the USB device.
    const std::string usb = "/sys/class/tty/" + tty + "/device/..";
    try {
      if (read_text(usb + "/idVendor") == hex4(config_.vendor_id) &&
          read_text(usb + "/idProduct") == hex4(config_.product_id) &&
          read_text(usb + "/serial") == config_.serial) {
        return tty;
      }
    } catch (const KernelFacilityError&) {
      // Not a USB device's, or going away while we look (a previous gadget's): not ours.
    }
  }
  return {};
}

void UsbAcmGadget::unplug() {
  if (!path_exists(root_ + "/UDC") || read_text(root_ + "/UDC").empty()) return;
  write_text(root_ + "/UDC", "\n");
  wait_until([&] { return find_host_tty().empty(); }, std::chrono::seconds(20),
             "the host side to drop gadget " + config_.name);
}

// Best effort and in reverse order; configfs refuses to remove a directory still in use.
void UsbAcmGadget::remove_configfs_tree() noexcept {
  if (!path_exists(root_)) return;
  try {
    unplug();
  } catch (const KernelFacilityError&) {
    // Removal below still runs; a later fixture reports what is left over.
  }
  ::unlink((root_ + "/configs/c.1/acm.usb0").c_str());
  remove_dir(root_ + "/configs/c.1/strings/0x409");
  remove_dir(root_ + "/configs/c.1");
  remove_dir(root_ + "/functions/acm.usb0");
  remove_dir(root_ + "/strings/0x409");
  remove_dir(root_);
}

}  // namespace hapticd::kernel_test
