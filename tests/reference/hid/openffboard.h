// A reference OpenFFBoard: the FFBWheel main class of github Ultrawipf/OpenFFBoard, firmware at
// commit 160af910, as a USB device on the raw gadget (raw_usb_hid.h). Written from that
// firmware's source, not from hapticd's codecs:
//   - its report descriptor (UserExtensions/Src/usb_hid_1ffb_desc.c, hid_1ffb_desc, and the
//     blocks of UserExtensions/Inc/usb_hid_ffb_desc.h): report 1 the gamepad (64 buttons, eight
//     16-bit axes), the vendor command reports 0xA1, and the PID reports with the ids of
//     Inc/ffb_defs.h (Set Effect 1, Envelope 2, Condition 3, Periodic 4, Constant 5, Ramp 6,
//     Effect Operation 0x0A, Block Free 0x0B, Device Control 0x0C, Device Gain 0x0D, Create New
//     Effect 0x11, Block Load 0x12, PID Pool 0x13; PID State input 2);
//   - FFBHIDMain::send_report: the gamepad report goes out only when it changed, or once
//     reportSendCounter passes 100 / usb_report_rate (about 100 report intervals) without one;
//     never while the IN endpoint is busy (tud_hid_n_ready);
//   - HidFFB: effects created by the Create New Effect feature report (type = its index in the
//     descriptor's list), Block Load and PID Pool answered through GET_REPORT, Device Control as
//     a byte of one-bit flags (1 enable, 2 disable, 4 stop all, 8 reset, 16 pause, 32
//     continue), Set Effect starting FFB when it is off, Block Free by index, and the PID State
//     report sent only from new_effect and set_effect: Actuator Power always, Actuators Enabled
//     and Effect Playing while FFB is on, Device Paused while it is off, and the declared Safety
//     Switch never;
//   - EffectsCalculator::calcComponentForce: a constant force's torque is `result_torque =
//     -forceVector * angle_ratio`, angle_ratio the X axis' share HidFFB::set_effect gives it
//     (sin(directionX), or (directionX - 18000) / 18000 without direction enable), times the
//     effect's gain and the device gain (/255 each); a finite effect stops that long after its
//     start. Axis.cpp inverts the angle and the torque together and its idle spring
//     (-pos_scaled_16b * idlespringscale) restores toward the centre: a positive torque moves
//     X up. So a positive magnitude at direction 90 degrees turns the wheel toward -X, at 270
//     toward +X: DirectInput's convention (90 degrees comes from +X).
// With `axes` 2 it is the FFB Joystick (2 Axis) main class instead (UserExtensions/Src/
// FFBJoystick.cpp lines 16 and 26: FFBHIDMain(2); line 39: hid_2ffb_desc): the same firmware
// with a second AxisPlant, Y, reported as the gamepad report's second axis (FFBHIDMain.cpp
// lines 192-202: axis i fills the report's axis i, usage Y 0x31). HidFFB::set_effect (lines
// 317-321) gives every effect a share per axis: with Direction Enable (bit 1 << axisCount,
// HidFFB.cpp line 17: 0x04 here) sin(directionX) for X and -cos(directionX) for Y; without,
// (directionX - 18000) / 18000 for X if Axes Enable X (bit 0), -(directionY - 18000) / 18000
// for Y if Axes Enable Y (bit 1), 0 for an axis not enabled. EffectsCalculator.cpp (lines
// 151-163) sums -magnitude * share (line 319) per axis over the playing effects and clips each
// axis' sum on its own.
// Left out: the optional constant-force low-pass filter (a delay a board may be configured
// with), conditions, periodic effects and the encoder hardware: the axis is AxisPlant, read
// every 1 ms FFB cycle.
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
#include "openffboard_descriptor.h"
#include "raw_usb_hid.h"

namespace hapticd::reference {

// Which way the X axis' share of an effect points.
enum class ForceSign {
  // OpenFFBoard's own (EffectsCalculator.cpp, calcComponentForce): torque = -magnitude *
  // sin(direction); DirectInput's convention.
  kOpenFfboard,
  // A firmware built on YukMingLaw/ArduinoJoystickWithFFBLibrary (v1.0.0, ed86e27e,
  // src/Joystick.cpp, getEffectForce: `angle_ratio = axis == 0 ? sin(angle) : ...`, force =
  // magnitude * angle_ratio): the reverse of DirectInput's, as its issue 36 ("Force direction
  // is backwards") reports. Everything else stays OpenFFBoard's, so one configuration drives
  // both boards and only the direction of the force differs.
  kArduinoJoystickWithFfbLibrary,
};

struct OpenFfboardOptions {
  std::string serial = "openffboard-ref";
  int axes = 1;                   // 1: FFBWheel; 2: FFB Joystick (2 Axis), X and Y
  double degrees = 900.0;         // axis.degrees: each axis spans +-degrees/2 at +-32767
  double torque_full_scale = 10;  // N m at magnitude 32767, both gains 255 (the power setting)
  double inertia = 0.05;          // the wheel, or each axis of the stick (kg m^2)
  double damping = 0.05;          // its own damping (N m s/rad), each axis
  double start_position = -0.1;   // rad, X
  double start_position_y = 0.0;  // rad, Y (two axes)
  std::size_t effects = 40;       // MAX_EFFECTS
  int usb_report_rate = 1;        // FFB cycles (1 ms) per send_report call
  ForceSign force_sign = ForceSign::kOpenFfboard;
};

class OpenFfboard {
 public:
  explicit OpenFfboard(const OpenFfboardOptions& o);
  ~OpenFfboard();  // unplugged

  // Axis 0 is X (the wheel), 1 is Y (two axes only).
  AxisPlant& axis(std::size_t i = 0) { return i == 0 ? axis_ : y_axis_; }
  // Effect blocks allocated now (created and not freed).
  std::size_t allocated() const;
  bool ffb_active() const { return ffb_active_.load(); }
  // An effect plays (started by Effect Operation, not stopped or expired).
  bool playing() const;
  std::uint64_t gamepad_reports() const { return reports_.load(); }
  // Output reports the host sent, and of them Set Constant Force (report 5): what reached the
  // board.
  std::uint64_t output_reports() const { return outputs_.load(); }
  std::uint64_t constant_reports() const { return constant_reports_.load(); }
  std::uint64_t set_effect_reports() const { return set_effect_reports_.load(); }
  // A test's own input report, as a broken firmware or a bad cable would hand one to the IN
  // endpoint beside the FFB loop's: false while the endpoint is busy (try again).
  bool send_raw_input(std::span<const std::uint8_t> report) { return usb_.send_input(report); }
  // The FFB main loop stops for good (a hung firmware): no more reports, the last torque
  // stays, and what the host sends is taken by the USB stack and never acted on.
  void hang() { hung_.store(true); }
  void unplug() { usb_.unplug(); }
  std::string error() const { return usb_.error(); }

  static constexpr std::uint16_t kVendor = 0x1209, kProduct = 0xFFB0;

 private:
  struct Effect {
    std::uint8_t type = 0;  // 0: free (FFB_EFFECT_NONE)
    bool playing = false;
    std::int16_t magnitude = 0;
    std::uint8_t gain = 255;
    double axis_magnitude[2] = {0.0, 0.0};  // FFB_Effect::axisMagnitudes, X and Y
    std::uint32_t duration_ms = 0xFFFF;     // FFB_EFFECT_DURATION_INFINITE
    std::int64_t start_ms = 0;
  };
  void main_loop();
  void send_report(int cycles);
  struct Torques {
    double x = 0.0, y = 0.0;  // N m
  };
  Torques torque(std::int64_t now_ms);
  void output(std::span<const std::uint8_t> r);
  bool create_effect(std::span<const std::uint8_t> r);
  std::optional<std::vector<std::uint8_t>> get_feature(std::uint8_t id);
  void set_effect(std::span<const std::uint8_t> r);
  void control(std::uint8_t bits);
  void status_report();
  std::int64_t now_ms() const;

  OpenFfboardOptions o_;
  AxisPlant axis_, y_axis_;
  mutable std::mutex m_;  // the effects and the PID state (USB handlers vs the FFB loop)
  std::vector<Effect> effects_;
  std::uint8_t device_gain_ = 255;
  std::uint8_t load_index_ = 1, load_status_ = 1;  // blockLoad_report
  std::atomic<bool> ffb_active_{false}, hung_{false}, stop_{false};
  std::atomic<std::uint64_t> reports_{0}, outputs_{0}, constant_reports_{0}, set_effect_reports_{0};
  std::vector<std::uint8_t> last_sent_;
  int send_counter_ = 0;  // reportSendCounter
  RawUsbHid usb_;
  std::thread loop_;
};

}  // namespace hapticd::reference
