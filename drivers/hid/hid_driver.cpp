#include "drivers/hid/hid_driver.h"

#include <fcntl.h>

#include <cerrno>
#include <cstring>

#include "drivers/hid/hid_config.h"
#include "drivers/hid/hid_device.h"
#include "drivers/hid/hidapi_transport.h"
#include "drivers/hid/socket_transport.h"
#include "sim/peers/hid/hidg_peer.h"
#include "sim/peers/hid/raw_gadget_peer.h"
#include "sim/peers/hid/socket_hid_peer.h"
#include "sim/peers/hid/uhid_peer.h"

namespace hapticd::drivers::hid {
namespace {

std::shared_ptr<const HidSettings> settings_of(const config::Config& cfg) {
  auto s = std::dynamic_pointer_cast<const HidSettings>(cfg.device.settings);
  if (!s) throw DeviceError("hid: the configuration has no device.hid section");
  return s;
}

int declared_delay(const config::Config& cfg) {
  return declared_delay_samples(settings_of(cfg)->poll_interval_ms, cfg.loop.sample_period_s());
}

std::unique_ptr<Device> make_device(const config::Config& cfg) {
  auto s = settings_of(cfg);
  return std::make_unique<HidDevice>(
      s, [s] { return open_hidapi(*s); }, cfg.loop.sample_period_s());
}

Loopback make_loopback(const config::Config& cfg) {
  auto s = settings_of(cfg);
  auto [ours, theirs] = io::seqpacket_pair();
  auto peer = std::make_unique<sim::hid::SocketHidPeer>(
      std::move(theirs), sim::hid::make_firmware(cfg, declared_delay(cfg)));
  // The device opens a duplicate at each configure, so it can be closed and configured again.
  auto end = std::make_shared<io::UniqueFd>(std::move(ours));
  const std::chrono::milliseconds timeout(static_cast<long>(s->limits.timeout_ms));
  auto open = [end, timeout]() -> std::unique_ptr<HidTransport> {
    io::UniqueFd fd(fcntl(end->get(), F_DUPFD_CLOEXEC, 0));
    if (!fd) throw DeviceError(std::string("hid loopback: dup: ") + std::strerror(errno));
    return std::make_unique<SocketTransport>(std::move(fd), timeout);
  };
  auto device = std::make_unique<HidDevice>(s, std::move(open), cfg.loop.sample_period_s());
  return {std::move(device), std::move(peer)};
}

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// /dev/hidgN (a USB HID gadget: usbhid, hidraw and libusb see a USB device, but f_hid answers
// no feature report), /dev/raw-gadget (a USB device this process answers for entirely,
// feature reports included) or /dev/uhid (a HID device made by the kernel's uhid: hidraw only,
// with feature reports).
std::unique_ptr<sim::LoopbackPeer> make_peer_on(const config::Config& cfg,
                                                const std::string& endpoint) {
  const auto s = settings_of(cfg);
  // On a real link the link is the delay: the simulated firmware adds none.
  auto firmware = sim::hid::make_firmware(cfg, 0);
  sim::hid::DeviceIdentity id;
  id.vendor_id = s->select.vendor_id.value_or(id.vendor_id);
  id.product_id = s->select.product_id.value_or(id.product_id);
  if (!s->select.serial.empty()) id.serial = s->select.serial;
  if (ends_with(endpoint, "uhid")) {
    return std::make_unique<sim::hid::UhidPeer>(endpoint, id, std::move(firmware));
  }
  if (ends_with(endpoint, "raw-gadget")) {
    return std::make_unique<sim::hid::RawGadgetPeer>(endpoint, id, std::move(firmware));
  }
  return std::make_unique<sim::hid::HidgPeer>(endpoint, std::move(firmware));
}

std::string list_devices() {
  std::string out;
  for (Backend b : {Backend::kHidraw, Backend::kLibusb}) {
    out += std::string("hid (") + to_string(b) + " backend):\n";
    try {
      out += format_listing(enumerate_devices(b), to_string(b));
    } catch (const DeviceError& e) {
      out += std::string("  cannot enumerate: ") + e.what() + "\n";
    }
  }
  return out;
}

}  // namespace

DriverEntry hid_driver() {
  DriverEntry e;
  e.name = "hid";
  e.summary = "USB HID through hidapi (hidraw or libusb): vendor reports or the PID page";
  e.read_section = read_hid_section;
  e.declared_delay = &declared_delay;
  e.make_device = &make_device;
  e.make_loopback = &make_loopback;
  e.make_peer_on = &make_peer_on;
  e.list_devices = &list_devices;
  return e;
}

}  // namespace hapticd::drivers::hid
