// The simulated HID device on a USB HID gadget: the function's /dev/hidgN is the device's
// end of a real USB link (dummy_hcd in the kernel test machine, or a UDC on a board), so the
// host meets it through usbhid, hidraw and libusb exactly as it meets hardware. What the host
// writes (hid_write: the interrupt OUT endpoint) is read here as an output report; what is
// written here goes out as an input report on the interrupt IN endpoint, one at a time as the
// host polls. The kernel's f_hid (Linux 6.1) stalls feature requests when the function has
// an OUT endpoint and answers GET_REPORT with zeros, so a profile that needs feature reports
// (pid; the report profile's *_feature keys) cannot run on it: see docs/drivers/hid.md.
//
// Firmware watchdog: without the host the plant does not step; if the host is silent longer
// than the firmware's watchdog (HidFirmware::watchdog_ms) while the output is on, the device
// drops to zero force and switches its output off, as the real firmware is configured to.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "drivers/io/unique_fd.h"
#include "sim/peers/hid/hid_firmware.h"

namespace hapticd::sim::hid {

class HidgPeer final : public FirmwarePeer {
 public:
  // Throws DeviceError when the endpoint cannot be opened.
  HidgPeer(const std::string& path, std::unique_ptr<HidFirmware> firmware);

  void service() override;
  int fd() const noexcept override { return fd_.get(); }
  int service_interval_ms() const noexcept override { return 5; }  // the watchdog's tick
  // The gadget cannot vanish from this side (the test unbinds it instead): kTransportFault
  // is refused.
  bool inject(PeerFault fault) noexcept override;

 private:
  void send(std::span<const std::uint8_t> report);

  std::string path_;
  io::UniqueFd fd_;
  std::vector<std::uint8_t> rx_ = std::vector<std::uint8_t>(1025);
};

}  // namespace hapticd::sim::hid
