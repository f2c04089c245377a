// A reference force-feedback board built on YukMingLaw/ArduinoJoystickWithFFBLibrary, v1.0.0
// (commit ed86e27e), as a USB device on the raw gadget (raw_usb_hid.h). Written from that
// library's source, not from hapticd's codecs:
//   - its report descriptor (arduino_ffb_descriptor.h): Device Control a 0x96 collection with
//     no 0x95 around it, one id shared by a feature and an output report (5, 6, 7), a PID State
//     report declared and never sent;
//   - src/DynamicHID/DynamicHID.cpp: GetReport answers feature 6 with the stored Block Load
//     structure and then sets its reportId to 0, so a second GET_REPORT reads id 0 with the old
//     bytes behind it; feature 7 (PID Pool) with ramPoolSize 0xFFFF, MAX_EFFECTS and
//     memoryManagement 3; SetReport takes feature 5 (Create New Effect) and nothing else;
//     RecvfromUsb hands every OUT report to PIDReportHandler::UppackUsbData;
//   - src/DynamicHID/PIDReportHandler.cpp: effect blocks numbered from 1 (nextEID), Create New
//     Effect taking the next free one (full at MAX_EFFECTS, 14), Block Free by index, Device
//     Control's value 1..6 (1 and 2 only flip a status bit: they switch no force; 3 stops all,
//     4 frees all, 5 and 6 pause and continue), StartEffect writing state = PLAYING over
//     ALLOCATED, and Effect Operation's loop count multiplying the duration;
//   - src/Joystick.cpp: getEffectForce's `angle = direction * 360 / 255` degrees and
//     `angle_ratio = axis == 0 ? sin(angle) : -cos(angle)` (a positive magnitude at 90 degrees
//     pushes toward +X: the reverse of DirectInput, its issue 36), ApplyGain/ApplyEnvelope,
//     forceCalculator's effect gains, total gain and `map(force, -10000, 10000, -250, 250)`,
//     all in the library's integer arithmetic; sendState's report 1 (buttons, then X, Y, Rx,
//     Ry as buildAndSet16BitValue maps them);
//   - examples/YourFirstFFBController: the sketch's loop reads the encoder, setXAxis (which
//     sends the report, Joystick.begin(true)), getForce, and drives the motor with
//     analogWrite(|forces[0]|) one way or the other by its sign; a timer interrupt calls
//     getUSBPID at 5 kHz.
// The sketch is the board's, not the library's: here its loop sends one report every
// `report_ms` (the example sends four a pass, for X, Y, Rx and Ry: the emulated USB controller
// of the kernel test machine cannot carry that), getForce and the motor run every millisecond
// in the timer interrupt beside getUSBPID (the example calls getForce from its loop, after
// setXAxis: there the emulated controller, which at times leaves an IN transfer untaken for
// over 100 ms, would hold the motor at a stale force while USB_Send waits, as no USB host on
// a cable does), its encoder has `counts_per_rad` counts per radian with
// setXAxisRange(-32767, 32767), and positive PWM turns the axis toward +X with `stall_torque`
// at analogWrite 255. ApplyEnvelope divides by the gained magnitude: for a
// magnitude of 0 (0 / 0, undefined in C++; avr-libgcc gives -1, which the later steps take to
// the same PWM 0) the reference takes 0.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "axis_plant.h"
#include "raw_usb_hid.h"

namespace hapticd::reference {

struct ArduinoFfbOptions {
  std::string serial = "arduino-ffb-ref";
  double counts_per_rad = 32767.0 / 3.14159265358979;  // X spans +-half a turn
  double stall_torque = 1.02;    // N m at analogWrite 255: 250 (Magnitude 10000) is 1 N m
  double inertia = 0.05;         // the axis (kg m^2)
  double damping = 0.05;         // its own damping (N m s/rad)
  double start_position = -0.1;  // rad
  int report_ms = 4;             // the sketch's loop: one joystick report this often
};

class ArduinoFfb {
 public:
  explicit ArduinoFfb(const ArduinoFfbOptions& o);
  ~ArduinoFfb();  // unplugged

  AxisPlant& axis() { return axis_; }
  // PIDReportHandler::nextEID: the block the next Create New Effect gets; 1 when every block
  // handed out was freed.
  int next_effect_id() const;
  // An effect plays (StartEffect'ed, not stopped, its duration not run out).
  bool playing() const;
  // The PWM the sketch last wrote (signed by the motor's direction pins), -250..250.
  int pwm() const { return pwm_.load(); }
  std::uint64_t reports() const { return reports_.load(); }
  // Output reports the host sent, and of them Set Constant Force: what reached the board.
  std::uint64_t output_reports() const { return outputs_.load(); }
  std::uint64_t constant_reports() const { return constants_.load(); }
  // What the board did, for a test that failed: its counts, where the axis is, and its first
  // PWM changes, each with the effects behind it.
  std::string describe() const;
  std::uint64_t block_load_reads() const { return block_load_reads_.load(); }
  // The longest a report waited for the host to take the last one (USB_Send, up to 250 ms)
  // once the host reads them.
  std::int64_t longest_wait_ms() const { return longest_wait_ms_.load(); }
  // The sketch's loop stops for good (a hung board): no more reports; the timer interrupt
  // still takes what the host sends and sets the motor by it.
  void hang() { hung_.store(true); }
  void unplug() { usb_.unplug(); }
  std::string error() const { return usb_.error(); }

  // Arduino SA's ids, as a Leonardo enumerates.
  static constexpr std::uint16_t kVendor = 0x2341, kProduct = 0x8036;
  static constexpr int kMaxEffects = 14;  // PIDReportType.h, MAX_EFFECTS

 private:
  // TEffectState, as far as a constant force needs it.
  struct Effect {
    std::uint8_t state = 0;  // 0 free, 1 allocated, 2 playing (StartEffect overwrites)
    std::uint8_t type = 0, gain = 0, enable_axis = 0, dir_x = 0, dir_y = 0;
    std::int16_t magnitude = 0;
    std::uint16_t duration = 0, elapsed = 0;
    std::int64_t start_ms = 0;
  };
  void sketch_loop();
  int force_calculator(std::int64_t now_ms);
  void note_change(std::int64_t now_ms, int pwm);
  void note_command(std::span<const std::uint8_t> report);
  std::int32_t effect_force(Effect& e, std::int64_t now_ms);
  void output(std::span<const std::uint8_t> r);
  bool set_feature(std::span<const std::uint8_t> r);
  std::optional<std::vector<std::uint8_t>> get_feature(std::uint8_t id);
  std::uint8_t next_free_effect();
  void set_effect(std::span<const std::uint8_t> r);
  void effect_operation(std::span<const std::uint8_t> r);
  void device_control(std::uint8_t control);
  std::vector<std::uint8_t> joystick_report() const;
  std::int64_t now_ms() const;

  ArduinoFfbOptions o_;
  AxisPlant axis_;
  mutable std::mutex m_;             // the effects (the timer interrupt vs the sketch's loop)
  Effect effects_[kMaxEffects + 1];  // g_EffectStates: index 0 unused, blocks 1..14
  std::uint8_t next_eid_ = 1;
  bool paused_ = false;
  std::uint8_t status_ = 30;  // pidState.status: never sent
  // pidBlockLoad: reportId, effectBlockIndex, loadStatus, ramPoolAvailable.
  std::uint8_t load_id_ = 0, load_block_ = 0, load_status_ = 0;
  std::uint16_t ram_available_ = 0;
  std::atomic<int> pwm_{0};
  std::vector<std::string> changes_;   // describe(): the first PWM changes
  std::vector<std::string> commands_;  // describe(): the first reports but Set Constant Force
  std::int64_t first_constant_ms_ = -1, last_constant_ms_ = -1;  // describe(): when they came
  std::atomic<std::int64_t> longest_wait_ms_{0};
  std::atomic<bool> hung_{false}, stop_{false};
  std::atomic<std::uint64_t> reports_{0}, block_load_reads_{0}, outputs_{0}, constants_{0},
      dropped_{0};
  RawUsbHid usb_;
  std::thread loop_;
};

}  // namespace hapticd::reference
