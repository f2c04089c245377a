// Reference vendor-report devices on uhid (hidraw): the kind of device `profile: report`
// drives, with the report layout that config/hid-report.yaml documents (input report 1: i16
// position in 10 um counts, u8 sample counter, u8 status; output report 2: i16 force in mN,
// u8 enable, u8 keep-alive), and the two timing behaviours real devices have that a loopback
// peer answering each command never shows:
//   - faster than the host's loop: a firmware sampling its encoder at its own rate and sending
//     every sample (several per host period), each numbered by its counter; optionally one
//     that really loses samples (its counter jumps);
//   - on change: a report only when the position count changed, and the unchanged one again
//     after a resend interval (the HID idle rate, HID 1.11 7.2.4, that most such devices keep).
// Written from those behaviours and the HID specification; it shares no code with sim/.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "axis_plant.h"
#include "uhid_device.h"

namespace hapticd::reference {

struct VendorDeviceOptions {
  std::string serial = "vendor-ref";
  double sample_hz = 400.0;  // the firmware's own loop: one report per cycle (or on change)
  bool on_change = false;    // report only when the count changed...
  double resend_ms = 200.0;  // ...or when this long passed without a report
  int lose_every = 0;        // every Nth report, `lost` samples vanish from the counter
  int lost = 5;
  double mass = 0.1, damping = 2.0, start_position = -0.01;  // kg, N s/m, m
};

class VendorDevice {
 public:
  explicit VendorDevice(const VendorDeviceOptions& o);
  ~VendorDevice();  // unplugged (UHID_DESTROY)

  AxisPlant& axis() { return axis_; }
  std::uint64_t reports() const { return reports_.load(); }
  bool output_on() const { return on_.load(); }
  double force() const { return force_.load(); }
  const std::string& hidraw() const { return uhid_->hidraw_path(); }

 private:
  void sample_loop();
  void output_loop();

  VendorDeviceOptions o_;
  AxisPlant axis_;
  std::unique_ptr<kernel_test::UhidDevice> uhid_;
  std::atomic<bool> stop_{false}, on_{false};
  std::atomic<double> force_{0.0};
  std::atomic<std::uint64_t> reports_{0};
  std::thread sampler_, listener_;
};

}  // namespace hapticd::reference
