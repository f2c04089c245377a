// The simulated HID device as a USB device of its own, through the kernel's raw gadget
// (/dev/raw-gadget): this process answers every control request itself, so the device
// enumerates on a USB device controller (dummy_hcd's in the kernel test machine, a board's
// UDC on real hardware) and the host meets it through usbhid, hidraw and libusb exactly as it
// meets a device on a cable, feature reports included. Linux 6.1's f_hid cannot do that
// (GET_REPORT answers zeros, SET_REPORT stalls while it has an OUT endpoint: hidg_peer.h),
// which the pid profile's Block Load and the report profile's feature keys need.
//
// Three threads: ep0 (control requests: descriptors, configuration, GET/SET_REPORT), the
// interrupt OUT endpoint (output reports of up to 64 bytes, one packet each) and the interrupt
// IN endpoint (input reports, one per host poll). A bus reset cancels the data transfers;
// those threads then wait for the host to configure the device again (Linux 6.1's raw gadget
// reports no reset, and a transfer queued too early would fail the gadget for good). Each blocks in
// the raw gadget's ioctls, which have no poll(2); stopping them sends SIGURG to each (a no-op
// handler installed without SA_RESTART, so the ioctl returns EINTR; SIGURG is not one of hapticd's
// stop signals and its default action is to ignore it). The firmware is not thread-safe: one mutex
// serialises every call into it. Not RT code: this is the device's side.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "drivers/io/unique_fd.h"
#include "sim/peers/hid/hid_firmware.h"
#include "sim/peers/hid/usb_hid_descriptors.h"

struct usb_ctrlrequest;

namespace hapticd::sim::hid {

class RawGadgetPeer final : public FirmwarePeer {
 public:
  // Opens `path` (/dev/raw-gadget), binds to the first USB device controller in
  // /sys/class/udc (its driver's name taken as its gadget name, which holds for dummy_hcd,
  // the one this is tested on) and starts the threads; the host enumerates the device
  // shortly after.
  // Throws DeviceError when the raw gadget or a controller is missing.
  RawGadgetPeer(const std::string& path, const DeviceIdentity& id,
                std::unique_ptr<HidFirmware> firmware);
  ~RawGadgetPeer() override;  // the device is unplugged: the host sees a disconnect
  RawGadgetPeer(const RawGadgetPeer&) = delete;
  RawGadgetPeer& operator=(const RawGadgetPeer&) = delete;

  // The firmware's watchdog; throws what a thread failed with (a transfer error that is not
  // the host going away).
  void service() override;
  int fd() const noexcept override { return timer_.get(); }  // never readable: a timer tick
  int service_interval_ms() const noexcept override { return 5; }
  // kTransportFault: the device is unplugged (its threads stopped, the gadget released).
  bool inject(PeerFault fault) noexcept override;
  // The device is unplugged: its threads end, so plant() may be read.
  void stop() noexcept override;

 private:
  void control_loop();
  void in_loop();
  void out_loop();
  // ep0: the answer to one request; false stalls it.
  bool answer_standard(const usb_ctrlrequest& r);
  bool answer_class(const usb_ctrlrequest& r);
  bool configure();
  void reply(const usb_ctrlrequest& r, std::span<const std::uint8_t> data);
  void acknowledge();
  // A control transfer that failed: the peer's end when the gadget itself is broken; else
  // that one request's (the host gave up on it, reset the bus), and the device goes on.
  void ep0_error(const char* what);
  void link_lost(std::uint64_t generation);
  void queue_input(std::span<const std::uint8_t> report);
  void fail(const std::string& what);
  void unplug() noexcept;

  UsbHidDescriptors usb_;
  io::UniqueFd gadget_, timer_;
  std::mutex fw_mutex_;  // every call into fw_
  std::mutex queue_mutex_;
  std::condition_variable queue_ready_;
  std::deque<std::vector<std::uint8_t>> queue_;  // input reports waiting for an IN poll
  int in_handle_ = -1, out_handle_ = -1;
  std::atomic<bool> stopping_{false}, configured_{false}, unplugged_{false};
  std::atomic<bool> link_up_{false};          // configured and not reset since: data may be queued
  std::atomic<std::uint64_t> generation_{0};  // SET_CONFIGURATIONs seen (after the first)
  std::mutex error_mutex_;
  std::string error_;
  std::thread control_, in_, out_;
  std::atomic<bool> control_done_{false}, in_done_{false}, out_done_{false};
};

}  // namespace hapticd::sim::hid
