// A reference haptic device that reports its position as the Nintendo Switch Pro Controller
// reports its left stick: the standard full-mode input report 0x30 (dekuNukem/
// Nintendo_Switch_Reverse_Engineering, bluetooth_hid_notes.md, "INPUT 0x30" and "Standard input
// report format", at commit ac8093c): after the id, byte 0 a timer, byte 1 the battery and
// connection nibbles, bytes 2-4 the buttons, bytes 5-7 the left stick and 8-10 the right, each
// two 12-bit axes packed three bytes to two (X = b5 | (b6 & 0x0f) << 8, Y = b6 >> 4 | b7 << 4:
// the notes' "Stick data" code, and Linux hid-nintendo.c, joycon_report_left_stick:
// hid_field_extract(rep->left_stick, 0, 12) and (rep->left_stick + 1, 4, 12)), byte 11 the
// vibrator report, bytes 12-47 the six-axis frames; pushed at the Pro Controller's 120 Hz, 64
// bytes a report over USB. The axis' position is the stick's X; its Y is a stick at rest
// that never sits still (a count either way), so the nibble it shares with X changes from
// report to report: a layout that reads X as a u16 reads Y's nibble into the position.
// The force comes in the vendor output report of config/hid-report.yaml (report 2: i16 force in
// mN, u8 enable, u8 keep-alive): a Pro Controller has no motor, so this is a device built on
// its report format, with a pid.codes test id (Nintendo's would bind hid-nintendo to it, which
// would wait for its handshake), on uhid, written from the sources above; it shares no code
// with sim/.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "axis_plant.h"
#include "uhid_device.h"

namespace hapticd::reference {

struct SwitchProStyleOptions {
  std::string serial = "switch-pro-style-ref";
  double metres_per_count = 2e-5;  // the stick's X: 2048 at 0, 0..4095 over +-41 mm
  double report_hz = 120.0;        // "Pushes current state ... @120Hz if Pro Controller"
  std::uint16_t y_rest = 1955;     // the stick's Y at rest (a count either way)
  double mass = 0.1, damping = 2.0, start_position = -0.01;  // kg, N s/m, m
};

class SwitchProStyle {
 public:
  explicit SwitchProStyle(const SwitchProStyleOptions& o);
  ~SwitchProStyle();  // unplugged (UHID_DESTROY)

  AxisPlant& axis() { return axis_; }
  std::uint64_t reports() const { return reports_.load(); }
  bool output_on() const { return on_.load(); }
  double force() const { return force_.load(); }

  static constexpr std::uint16_t kVendor = 0x1209, kProduct = 0x0003;
  static constexpr std::uint8_t kInputId = 0x30, kOutputId = 2;

 private:
  void firmware_loop();
  void output_loop();

  SwitchProStyleOptions o_;
  AxisPlant axis_;
  std::unique_ptr<kernel_test::UhidDevice> uhid_;
  std::atomic<bool> stop_{false}, on_{false};
  std::atomic<double> force_{0.0};
  std::atomic<std::uint64_t> reports_{0};
  std::thread firmware_, listener_;
};

}  // namespace hapticd::reference
