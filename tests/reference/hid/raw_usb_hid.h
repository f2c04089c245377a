// A USB HID device on the kernel's raw gadget (/dev/raw-gadget on dummy_hcd in the kernel test
// machine), written for the reference devices from the USB 2.0 specification (chapter 9: the
// standard requests and descriptors), the HID 1.11 specification (7.1 descriptors, 7.2 class
// requests: GET_REPORT, SET_REPORT, SET_IDLE) and the raw gadget's interface
// (include/uapi/linux/usb/raw_gadget.h). It shares no code with sim/: a reference device meets
// the host the way a microcontroller's USB stack (tinyusb, in OpenFFBoard) does, and the host
// (usbhid, hidraw, libusb) cannot tell it from one on a cable.
//
// Like tinyusb's HID class it keeps one input report in flight: send_input() refuses while the
// previous one has not been taken by an IN poll (tud_hid_n_ready() false), so a firmware that
// sends faster than the host polls learns so, as on hardware. Output reports arrive by the
// interrupt OUT endpoint, or by SET_REPORT on ep0; feature reports by SET_REPORT and
// GET_REPORT. Three threads block in the raw gadget's ioctls (ep0, IN, OUT); SIGURG (an empty
// handler without SA_RESTART) interrupts them at the end. Not RT code.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

namespace hapticd::reference {

struct UsbIdentity {
  std::uint16_t vendor_id = 0x1209;
  std::uint16_t product_id = 0x0001;
  std::uint16_t release = 0x0100;  // bcdDevice
  std::string manufacturer = "reference";
  std::string product = "reference HID device";
  std::string serial = "0";
};

// What the firmware answers. Reports carry their id first when the descriptor numbers them.
struct UsbHidHandlers {
  // An output report (interrupt OUT, or SET_REPORT of type output).
  std::function<void(std::span<const std::uint8_t>)> output;
  // SET_REPORT of a feature report; false stalls it.
  std::function<bool(std::span<const std::uint8_t>)> set_feature;
  // GET_REPORT of feature report `id`: its data without the id (the stack prepends it, as
  // tinyusb does), or nothing to stall the request.
  std::function<std::optional<std::vector<std::uint8_t>>(std::uint8_t id)> get_feature;
};

class RawUsbHid {
 public:
  // Binds to the first controller in /sys/class/udc and starts the threads; the host
  // enumerates the device shortly after. Throws std::runtime_error when it cannot.
  RawUsbHid(const UsbIdentity& id, std::vector<std::uint8_t> report_descriptor,
            UsbHidHandlers handlers, bool report_ids);
  ~RawUsbHid();  // unplug()
  RawUsbHid(const RawUsbHid&) = delete;
  RawUsbHid& operator=(const RawUsbHid&) = delete;

  // Any thread. Hands one input report to the IN endpoint; false while the previous one is
  // still waiting for the host (nothing is queued behind it), or before the host configured
  // the device.
  bool send_input(std::span<const std::uint8_t> report);
  bool configured() const noexcept { return link_up_.load(); }
  // The cable is pulled: the threads end and the host sees a disconnect. Idempotent.
  void unplug() noexcept;
  // A transfer or the gadget failed ("" if not): the device's own fault, not the host's.
  std::string error() const;

 private:
  void control_loop();
  void in_loop();
  void out_loop();
  bool standard(const void* request);
  bool hid_class(const void* request);
  void reply(std::uint16_t asked, std::span<const std::uint8_t> data);
  void ack();
  bool configure();
  void wait_for_host(std::uint64_t generation);
  void fail(const char* what);

  UsbIdentity id_;
  std::vector<std::uint8_t> report_descriptor_, device_desc_, config_desc_;
  UsbHidHandlers handlers_;
  bool report_ids_;
  int fd_ = -1;
  int in_ep_ = -1, out_ep_ = -1;
  std::mutex m_;          // the IN slot, the generation
  std::mutex handler_m_;  // one handler call at a time (they may call send_input)
  std::condition_variable cv_;
  std::optional<std::vector<std::uint8_t>> in_slot_;
  std::atomic<bool> stopping_{false}, link_up_{false}, endpoints_{false}, unplugged_{false};
  std::uint64_t generation_ = 0;  // SET_CONFIGURATIONs seen: a reset ends one
  mutable std::mutex error_m_;
  std::string error_;
  std::thread control_, in_, out_;
  std::atomic<bool> control_done_{false}, in_done_{false}, out_done_{false};
};

}  // namespace hapticd::reference
