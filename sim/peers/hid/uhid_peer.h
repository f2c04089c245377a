// The simulated HID device made through /dev/uhid: the kernel's HID core (hid-generic, hidraw)
// takes it as a device on a cable, so the hidraw backend meets it exactly as it meets
// hardware, feature reports included (UHID_GET_REPORT / UHID_SET_REPORT are answered by the
// firmware), which Linux 6.1's USB HID gadget cannot do. `hapticd peer --endpoint /dev/uhid`
// makes one with device.hid.select's vendor_id, product_id and serial; it is not a USB device,
// so hidapi's libusb backend cannot see it. The firmware's watchdog runs in wall time as on
// the gadget (hidg_peer.h).
#pragma once

#include <memory>
#include <string>

#include "drivers/io/unique_fd.h"
#include "sim/peers/hid/device_identity.h"
#include "sim/peers/hid/hid_firmware.h"

namespace hapticd::sim::hid {

class UhidPeer final : public FirmwarePeer {
 public:
  // Creates the device (UHID_CREATE2 with the firmware's descriptor). Throws DeviceError when
  // /dev/uhid cannot be used.
  UhidPeer(const std::string& path, const DeviceIdentity& id,
           std::unique_ptr<HidFirmware> firmware);
  ~UhidPeer() override;  // UHID_DESTROY: the device disappears like an unplugged one

  void service() override;
  int fd() const noexcept override { return fd_.get(); }
  int service_interval_ms() const noexcept override { return 5; }  // the watchdog's tick
  // kTransportFault: the device is destroyed, as if unplugged.
  bool inject(PeerFault fault) noexcept override;

 private:
  void send_input(std::span<const std::uint8_t> report);

  io::UniqueFd fd_;
  std::atomic<bool> destroyed_{false};
};

}  // namespace hapticd::sim::hid
