#include "sim/peers/hid/hid_peer_entry.h"

#include "drivers/device.h"
#include "drivers/hid/hid_settings.h"
#include "sim/peers/hid/hid_endpoint.h"
#include "sim/peers/hid/hid_firmware.h"
#include "sim/peers/hid/hidg_peer.h"
#include "sim/peers/hid/raw_gadget_peer.h"
#include "sim/peers/hid/socket_hid_peer.h"
#include "sim/peers/hid/uhid_peer.h"

namespace hapticd::sim::hid {
namespace {

const drivers::hid::HidSettings& settings_of(const config::Config& cfg) {
  const auto* s = dynamic_cast<const drivers::hid::HidSettings*>(cfg.device.settings.get());
  if (s == nullptr) throw DeviceError("hid peer: the configuration has no device.hid section");
  return *s;
}

std::unique_ptr<LoopbackPeer> make_peer(const config::Config& cfg, io::UniqueFd end) {
  // Over the socketpair the firmware holds each answer as long as the USB link would: the
  // delay the driver declares, from the same polling interval.
  const int delay =
      drivers::hid::declared_delay_samples(settings_of(cfg), cfg.loop.sample_period_s());
  return std::make_unique<SocketHidPeer>(std::move(end), make_firmware(cfg, delay));
}

// /dev/hidgN (a USB HID gadget: usbhid, hidraw and libusb see a USB device, but f_hid answers
// no feature report), /dev/raw-gadget (a USB device this process answers for entirely,
// feature reports included) or /dev/uhid (a HID device made by the kernel's uhid: hidraw only,
// with feature reports).
std::unique_ptr<LoopbackPeer> make_peer_on(const config::Config& cfg, const std::string& endpoint) {
  const drivers::hid::HidSettings& s = settings_of(cfg);
  // On a real link the link is the delay: the simulated firmware adds none.
  auto firmware = make_firmware(cfg, 0);
  DeviceIdentity id;
  id.vendor_id = s.select.vendor_id.value_or(id.vendor_id);
  id.product_id = s.select.product_id.value_or(id.product_id);
  if (!s.select.serial.empty()) id.serial = s.select.serial;
  if (endpoint_is(endpoint, "uhid")) {
    return std::make_unique<UhidPeer>(endpoint, id, std::move(firmware));
  }
  if (endpoint_is(endpoint, "raw-gadget")) {
    return std::make_unique<RawGadgetPeer>(endpoint, id, std::move(firmware));
  }
  return std::make_unique<HidgPeer>(endpoint, std::move(firmware));
}

}  // namespace

PeerEntry peer_entry() {
  PeerEntry e;
  e.driver = "hid";
  e.make_peer = &make_peer;
  e.make_peer_on = &make_peer_on;
  e.judge_endpoint = &judge_endpoint;
  return e;
}

}  // namespace hapticd::sim::hid
