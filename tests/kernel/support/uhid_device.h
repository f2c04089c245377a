// A HID device made from user space through /dev/uhid: the kernel's HID core (hid-generic,
// hidraw) handles it as it would a real one, so hidraw and hidapi's hidraw backend see it.
// Lighter than UsbHidGadget (no USB), invisible to libusb. The fixture is the device end:
// send_input() delivers input reports, read_output() returns what the host wrote.
#pragma once

#include <linux/uhid.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "unique_fd.h"

namespace hapticd::kernel_test {

struct UhidConfig {
  std::vector<std::uint8_t> report_descriptor;  // e.g. vendor_report_descriptor()
  std::uint16_t bus = 0x03;                     // BUS_USB: hidapi reports it as a USB device
  std::uint16_t vendor_id = 0x1209;
  std::uint16_t product_id = 0x0002;
  std::string name = "hapticd uhid test device";
  std::string serial = "hapticd-uhid";  // uniq: hidapi's serial number
};

class UhidDevice {
 public:
  // Creates the device and waits (up to 10 s) until the kernel started it and made hidraw.
  explicit UhidDevice(UhidConfig config);
  ~UhidDevice();  // UHID_DESTROY: the device disappears like an unplugged one
  UhidDevice(const UhidDevice&) = delete;
  UhidDevice& operator=(const UhidDevice&) = delete;

  const UhidConfig& config() const noexcept { return config_; }
  const std::string& hidraw_path() const noexcept { return hidraw_path_; }
  int fd() const noexcept { return fd_.get(); }

  // One input report as the device sends it (report id first for numbered reports).
  void send_input(const std::vector<std::uint8_t>& report);
  // The next output report the host wrote (UHID_OUTPUT), or nothing within TIMEOUT. Other
  // events met on the way (open, close) update is_open().
  std::optional<std::vector<std::uint8_t>> read_output(
      std::chrono::milliseconds timeout = std::chrono::seconds(5));
  // Whether some process has the device open (the last UHID_OPEN/UHID_CLOSE seen).
  bool is_open() const noexcept { return open_; }

 private:
  // Reads one event if one arrives within TIMEOUT.
  std::optional<uhid_event> next_event(std::chrono::milliseconds timeout);
  void write_event(const uhid_event& event, const char* what);

  UhidConfig config_;
  UniqueFd fd_;
  std::string hidraw_path_;
  bool open_ = false;
};

}  // namespace hapticd::kernel_test
