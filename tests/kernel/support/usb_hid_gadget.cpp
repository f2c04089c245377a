#include "usb_hid_gadget.h"

#include <fcntl.h>
#include <linux/input.h>
#include <poll.h>
#include <unistd.h>

#include <cstdio>
#include <sstream>

#include "hid_support.h"
#include "sysfs.h"
#include "usb_gadget_tree.h"

namespace hapticd::kernel_test {
namespace {

// The /dev node of the character device "major:minor", as devtmpfs names it.
std::string char_device_node(const std::string& major_minor) {
  std::istringstream uevent(read_text("/sys/dev/char/" + major_minor + "/uevent"));
  for (std::string line; std::getline(uevent, line);) {
    if (line.rfind("DEVNAME=", 0) == 0) return "/dev/" + line.substr(8);
  }
  throw KernelFacilityError("no DEVNAME for character device " + major_minor);
}

}  // namespace

UsbHidGadget::UsbHidGadget(UsbHidGadgetConfig config)
    : config_(std::move(config)), root_(std::string(kUsbGadgets) + "/" + config_.name) {
  require_path(kUsbGadgets, "USB gadget configfs (libcomposite, configfs mounted)");
  const auto controllers = list_dir("/sys/class/udc");
  if (controllers.empty()) throw KernelFacilityError("no USB device controller (dummy_hcd)");
  try {
    create_configfs_tree();
    write_text(root_ + "/UDC", controllers.front());
    // The host side enumerates asynchronously: the USB device first, then usbhid's hidraw.
    wait_until(
        [&] {
          return find_usb_device() &&
                 find_hidraw(BUS_USB, config_.vendor_id, config_.product_id, config_.serial);
        },
        std::chrono::seconds(20), "the USB host side to enumerate gadget " + config_.name);
    usb_device_path_ = *find_usb_device();
    hidraw_path_ = *find_hidraw(BUS_USB, config_.vendor_id, config_.product_id, config_.serial);
    hidg_path_ = char_device_node(read_text(root_ + "/functions/hid.usb0/dev"));
    hidg_.reset(::open(hidg_path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC));
    if (!hidg_) throw_errno("open " + hidg_path_);
  } catch (...) {
    remove_configfs_tree();
    throw;
  }
}

UsbHidGadget::~UsbHidGadget() {
  hidg_.reset();
  remove_configfs_tree();
}

void UsbHidGadget::create_configfs_tree() {
  const std::string function =
      make_gadget_tree(root_,
                       {config_.vendor_id, config_.product_id, config_.serial, config_.manufacturer,
                        config_.product},
                       "hid", "hid.usb0");
  write_text(function + "/protocol", "0");
  write_text(function + "/subclass", "0");
  write_text(function + "/report_length", std::to_string(config_.report_length));
  write_text(function + "/report_desc",
             std::string(config_.report_descriptor.begin(), config_.report_descriptor.end()));
  link_gadget_function(root_, "hid.usb0");
}

// Best effort and in reverse order; configfs refuses to remove a directory still in use.
void UsbHidGadget::remove_configfs_tree() noexcept {
  if (!path_exists(root_)) return;
  try {
    if (!read_text(root_ + "/UDC").empty()) write_text(root_ + "/UDC", "\n");
    // Let the host side finish the disconnect, so a next gadget with the same ids and
    // serial is never confused with this one's leftovers.
    wait_until(
        [&] {
          return !find_hidraw(BUS_USB, config_.vendor_id, config_.product_id, config_.serial);
        },
        std::chrono::seconds(5), "the host side to drop gadget " + config_.name);
  } catch (const KernelFacilityError&) {
    // Removal below still runs; a later fixture reports what is left over.
  }
  remove_gadget_tree(root_, "hid.usb0");
}

std::optional<std::string> UsbHidGadget::find_usb_device() const {
  const std::string devices = "/sys/bus/usb/devices/";
  for (const auto& dev : list_dir(devices)) {
    const std::string dir = devices + dev;
    if (!path_exists(dir + "/idVendor") || !path_exists(dir + "/serial")) continue;
    if (read_text(dir + "/idVendor") != hex4(config_.vendor_id) ||
        read_text(dir + "/idProduct") != hex4(config_.product_id) ||
        read_text(dir + "/serial") != config_.serial) {
      continue;
    }
    char node[32];
    std::snprintf(node, sizeof node, "/dev/bus/usb/%03d/%03d",
                  std::stoi(read_text(dir + "/busnum")), std::stoi(read_text(dir + "/devnum")));
    return std::string(node);
  }
  return std::nullopt;
}

void UsbHidGadget::write_input_report(const std::vector<std::uint8_t>& report,
                                      std::chrono::milliseconds timeout) {
  pollfd pfd{hidg_.get(), POLLOUT, 0};
  const int ready = ::poll(&pfd, 1, static_cast<int>(timeout.count()));
  if (ready < 0) throw_errno("poll " + hidg_path_);
  if (ready == 0) {
    throw KernelFacilityError("the host did not take the previous input report within " +
                              std::to_string(timeout.count()) + " ms (is the device open?)");
  }
  const ssize_t n = ::write(hidg_.get(), report.data(), report.size());
  if (n != static_cast<ssize_t>(report.size())) throw_errno("write " + hidg_path_);
}

std::optional<std::vector<std::uint8_t>> UsbHidGadget::read_output_report(
    std::chrono::milliseconds timeout) {
  pollfd pfd{hidg_.get(), POLLIN, 0};
  const int ready = ::poll(&pfd, 1, static_cast<int>(timeout.count()));
  if (ready < 0) throw_errno("poll " + hidg_path_);
  if (ready == 0) return std::nullopt;
  std::vector<std::uint8_t> report(config_.report_length);
  const ssize_t n = ::read(hidg_.get(), report.data(), report.size());
  if (n < 0) throw_errno("read " + hidg_path_);
  report.resize(static_cast<std::size_t>(n));
  return report;
}

}  // namespace hapticd::kernel_test
