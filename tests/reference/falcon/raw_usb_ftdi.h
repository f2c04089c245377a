// The reference Falcon's FT232 on the kernel's raw gadget (/dev/raw-gadget on dummy_hcd in
// the kernel test machine): the USB face of falcon_firmware.h. Written from USB 2.0 chapter 9,
// the raw gadget's interface (include/uapi/linux/usb/raw_gadget.h) and what libnifalcon
// (f7c727aa, src/comm/FalconCommLibUSB.cpp) and libftdi's request numbers show of the chip:
// vendor requests on ep0, bulk OUT 0x02 to the chip, bulk IN 0x81 with two modem status bytes
// (0x31 0x60: CTS, DSR; transmitter empty) at the head of every 64-byte packet. It shares no
// code with hid/raw_usb_hid.cpp beyond its structure: three threads block in the raw gadget's
// ioctls (ep0, IN, OUT) and SIGURG (no SA_RESTART) interrupts them.
//
// The IN side, and why it is shaped so: dummy_hcd keeps one IN packet of up to 64 bytes in a
// slot of its own and completes the device's request at once, so a packet queued there before
// the host purged the chip still reaches the host after the purge (a real FT232 sends only
// when polled). So here, while the firmware runs, the slot always holds a bare status first
// (harmless if stale: libnifalcon's runIOLoop skips modem-only reads), and data waits behind it
// as a request of its own that a purge takes back (SIGURG: the raw gadget dequeues an
// interrupted request); a bare status behind it is replaced when data arrives, and one more is
// sent per latency period while nothing else is, as the chip does. In the bootloader nothing
// but answers is sent: libnifalcon reads each answer right after its write, and its 'A' read
// is 3 bytes long, which a bare status queued ahead would fail (a real chip's latency timer,
// 16 ms there, does not run out before the bootloader's answer).
// Not RT code.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "falcon_firmware.h"

namespace hapticd::reference::falcon {

struct FtdiIdentity {
  std::uint16_t vendor_id = 0x0403;   // FTDI
  std::uint16_t product_id = 0xCB48;  // Novint Falcon
  std::uint16_t release = 0x0600;     // bcdDevice of an FT232R
  std::string manufacturer = "Novint Technologies Inc.";
  std::string product = "FALCON HAPTIC";
  std::string serial = "FHS00001";
};

// Whether the host's kernel lists a device of `id`'s vendor and product in /sys/bus/usb/devices
// (enumerated it): libusb scans sysfs as it starts, and the machine runs no udevd.
bool listed_in_sysfs(const FtdiIdentity& id = {});

class RawUsbFtdi {
 public:
  // Binds to the first controller in /sys/class/udc and starts the threads; the host
  // enumerates the device shortly after. Throws std::runtime_error when it cannot.
  explicit RawUsbFtdi(const FirmwareOptions& options = {}, const FtdiIdentity& id = {});
  ~RawUsbFtdi();  // unplug()
  RawUsbFtdi(const RawUsbFtdi&) = delete;
  RawUsbFtdi& operator=(const RawUsbFtdi&) = delete;

  // Runs f on the firmware model under the device's lock (the USB threads use it too).
  template <class F>
  auto with_firmware(F&& f) {
    const std::lock_guard lock(m_);
    return f(firmware_);
  }
  bool configured() const noexcept { return link_up_.load(); }
  // The cable is pulled: the threads end and the host sees a disconnect. Idempotent.
  void unplug() noexcept;
  // A transfer or the gadget failed ("" if not): the device's own fault, not the host's.
  std::string error() const;
  std::uint64_t data_packets() const { return data_packets_.load(); }
  std::uint64_t status_packets() const { return status_packets_.load(); }
  std::uint64_t withdrawn() const { return withdrawn_.load(); }

 private:
  void control_loop();
  void in_loop();
  void out_loop();
  bool standard(const void* request);
  bool vendor(const void* request);
  void reply(std::uint16_t asked, const std::vector<std::uint8_t>& data);
  void ack();
  bool configure();
  void wait_for_host(std::uint64_t generation);
  bool next_packet(std::vector<std::uint8_t>& packet, std::uint64_t& generation, bool slot_taken,
                   bool& decoy);
  void withdraw(bool status_only);
  void fail(const char* what);
  double now() const;

  FtdiIdentity id_;
  FalconFirmware firmware_;
  std::vector<std::uint8_t> device_desc_, config_desc_;
  int fd_ = -1;
  int in_ep_ = -1, out_ep_ = -1;
  std::mutex m_;  // the firmware, the IN state, the generation
  std::condition_variable cv_;
  bool in_flight_ = false, in_flight_status_ = false;
  std::uint64_t in_seq_ = 0;            // IN packets queued
  std::uint64_t in_flight_purges_ = 0;  // the firmware's purges when it was queued
  std::chrono::steady_clock::time_point last_in_{};
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::atomic<bool> stopping_{false}, link_up_{false}, endpoints_{false}, unplugged_{false};
  std::uint64_t generation_ = 0;  // SET_CONFIGURATIONs seen: a reset ends one
  std::atomic<std::uint64_t> data_packets_{0}, status_packets_{0}, withdrawn_{0};
  mutable std::mutex error_m_;
  std::string error_;
  std::thread control_, in_, out_;
  std::atomic<bool> control_done_{false}, in_done_{false}, out_done_{false};
};

}  // namespace hapticd::reference::falcon
