// A real USB HID device inside the kernel test machine: a configfs gadget with one HID
// function on the dummy_hcd controller, so the kernel's USB host side enumerates it like a
// device on a cable (usbhid binds, hidraw appears, libusb sees it under /dev/bus/usb).
// /dev/hidgN is the device's end: what a test writes there is an input report on the
// interrupt IN endpoint; what the host sends (hid_write) is read there as an output report.
//
// dummy_hcd has one controller, so one gadget at a time. Feature reports (GET/SET_REPORT on
// the control endpoint) are not answered by this fixture. The guest runs no udevd, and libusb
// (built with udev support) only learns of devices plugged in after libusb_init() from udevd:
// create the gadget before libusb or hidapi-libusb initialise.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "unique_fd.h"

namespace hapticd::kernel_test {

struct UsbHidGadgetConfig {
  std::vector<std::uint8_t> report_descriptor;  // e.g. vendor_report_descriptor()
  std::uint16_t vendor_id = 0x1209;             // pid.codes' test vendor id
  std::uint16_t product_id = 0x0001;
  std::string serial = "hapticd-test";
  std::string manufacturer = "hapticd";
  std::string product = "hapticd test device";
  std::uint16_t report_length = 64;  // wMaxPacketSize of both interrupt endpoints
  std::string name = "hapticd";      // the configfs directory under usb_gadget/
};

class UsbHidGadget {
 public:
  // Creates the gadget, binds it to the dummy controller and waits (up to 20 s: emulated
  // machines are slow) until the host side has enumerated it and made its hidraw node.
  explicit UsbHidGadget(UsbHidGadgetConfig config);
  ~UsbHidGadget();  // unbinds (the host sees a disconnect) and removes the configfs tree
  UsbHidGadget(const UsbHidGadget&) = delete;
  UsbHidGadget& operator=(const UsbHidGadget&) = delete;

  const UsbHidGadgetConfig& config() const noexcept { return config_; }
  // The device end, /dev/hidgN, open read-write and non-blocking.
  int fd() const noexcept { return hidg_.get(); }
  const std::string& hidg_path() const noexcept { return hidg_path_; }
  // The host end the kernel made: /dev/hidrawN, and the USB device node /dev/bus/usb/BBB/DDD.
  const std::string& hidraw_path() const noexcept { return hidraw_path_; }
  const std::string& usb_device_path() const noexcept { return usb_device_path_; }

  // Sends one input report (report id first for numbered reports). Waits until the previous
  // one has been taken by the host, which polls only while someone has the device open.
  void write_input_report(const std::vector<std::uint8_t>& report,
                          std::chrono::milliseconds timeout = std::chrono::seconds(5));
  // The next output report the host sent, or nothing within TIMEOUT.
  std::optional<std::vector<std::uint8_t>> read_output_report(
      std::chrono::milliseconds timeout = std::chrono::seconds(5));

 private:
  void create_configfs_tree();
  void remove_configfs_tree() noexcept;
  std::optional<std::string> find_usb_device() const;

  UsbHidGadgetConfig config_;
  std::string root_;  // /sys/kernel/config/usb_gadget/<name>
  UniqueFd hidg_;
  std::string hidg_path_, hidraw_path_, usb_device_path_;
};

}  // namespace hapticd::kernel_test
