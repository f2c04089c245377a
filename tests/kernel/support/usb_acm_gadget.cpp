#include "usb_acm_gadget.h"

#include "sysfs.h"
#include "usb_gadget_tree.h"

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
  make_gadget_tree(root_,
                   {config_.vendor_id, config_.product_id, config_.serial, config_.manufacturer,
                    config_.product},
                   "acm", "acm.usb0");
  link_gadget_function(root_, "acm.usb0");
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
  remove_gadget_tree(root_, "acm.usb0");
}

}  // namespace hapticd::kernel_test
