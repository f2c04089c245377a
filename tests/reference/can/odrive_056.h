// An ODrive v3 axis as firmware 0.5.6 behaves on CAN (github odriverobotics/ODrive, tag
// fw-v0.5.6), written from that source, sharing nothing with drivers/:
//
// - communication/can/can_simple.cpp: ids node << 5 | cmd (can_simple.hpp's enum: 0x000
//   CANopen NMT - ignored, 0x001 heartbeat, 0x007 Set_Axis_State, 0x009 Get_Encoder_Estimates,
//   0x00B Set_Controller_Modes, 0x00E Set_Input_Torque, 0x018 Clear_Errors, 0x01D
//   Get_Controller_Error); do_command feeds the axis watchdog for EVERY frame addressed to
//   the axis, before anything else; remote requests answered for the Get_* commands only (a
//   heartbeat RTR is fed on and otherwise ignored); service_stack sends the heartbeat every
//   config.can.heartbeat_rate_ms (default 100) and the encoder estimates every
//   config.can.encoder_rate_ms (default 10) whatever else is asked. Heartbeat: axis error
//   u32, state u8, motor/encoder/controller error flags (controller: bit 7 trajectory done).
// - MotorControl/main.cpp (ODrive::control_loop_cb) and axis.cpp: watchdog_check runs on every
//   control-loop pass for every axis in every state: with config.enable_watchdog, once
//   config.watchdog_timeout passes without a feed it sets WATCHDOG_TIMER_EXPIRED and keeps
//   setting it on every pass until fed (so a clear without a feed does not stick); the timer
//   starts at boot (apply_config feeds it). Any axis error disarms the motor: closed loop
//   ends in IDLE. ODrive::clear_errors clears the axis, motor, encoder and controller errors.
// - MotorControl/controller.cpp (Controller::update, limitVel) and controller.hpp defaults: in
//   torque control with enable_torque_mode_vel_limit the torque is clamped to
//   [(-vel_limit - vel) vel_gain, (vel_limit - vel) vel_gain]; with enable_overspeed_error,
//   |vel| > vel_limit_tolerance x vel_limit sets controller error OVERSPEED (0x1) and the
//   axis CONTROLLER_FAILED (0x200). vel_limit 2 turn/s, tolerance 1.2, vel_gain 1/6 N m/(turn/s).
// - odrive-interface.yaml: axis error bits (WATCHDOG_TIMER_EXPIRED bit 11, CONTROLLER_FAILED
//   bit 9), axis states (IDLE 1, CLOSED_LOOP_CONTROL 8), control mode torque 1.
//
// The control loop is not run at 8 kHz here: each frame and each 1 ms service runs one pass
// at the current time (the watchdog compares times, the plant advances in real time).
// Position and velocity control are not modelled: in those modes the axis applies no torque
// and counts it (unmodelled_mode_passes), so a test can insist it never happened.
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "reference/can/can_wire.h"
#include "reference/can/reference_plant.h"
#include "reference/can/reference_runner.h"

namespace hapticd::reference {

struct Odrive056Config {
  std::uint8_t node = 1;
  bool enable_watchdog = true;
  double watchdog_timeout_s = 0.25;
  std::uint32_t heartbeat_rate_ms = 100;  // axis.config.can.heartbeat_rate_ms
  std::uint32_t encoder_rate_ms = 10;     // axis.config.can.encoder_rate_ms
  // controller.config, firmware defaults
  double vel_limit = 2.0;  // turn/s
  double vel_limit_tolerance = 1.2;
  double vel_gain = 1.0 / 6.0;  // N m / (turn/s)
  bool enable_torque_mode_vel_limit = true;
  bool enable_overspeed_error = true;
  // The axis behind the motor: metres per motor turn, and the motor torque per axis newton.
  double metres_per_turn = 0.09817477042468103;
  double nm_per_newton = 0.015625;
};

class Odrive056 final : public ReferenceDevice {
 public:
  static constexpr std::uint32_t kWatchdogExpired = 0x00000800;
  static constexpr std::uint32_t kControllerFailed = 0x00000200;
  static constexpr std::uint32_t kMotorFailed = 0x00000040;
  static constexpr std::uint32_t kOverspeed = 0x00000001;  // controller error
  static constexpr std::uint8_t kIdle = 1;
  static constexpr std::uint8_t kClosedLoop = 8;

  // Power-on at now_ns.
  Odrive056(const Odrive056Config& c, const PlantParameters& plant, std::int64_t now_ns);

  // The drive's thread: one frame from the bus; what it answers goes to `out`.
  void on_frame(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) override;
  // The drive's thread, at least every millisecond: a control-loop pass and the cyclic messages.
  void on_clock(std::int64_t now_ns, std::vector<Frame>& out) override;

  // Any thread.
  std::uint8_t state() const { return state_.load(); }
  std::uint32_t axis_error() const { return error_.load(); }
  std::uint32_t controller_error() const { return controller_error_.load(); }
  bool armed() const { return state() == kClosedLoop; }
  double position_m() const { return plant_.position_now(); }
  double motor_force_n() const { return plant_.motor_force_now(); }
  // The hand starts pushing now (a test: once hapticd has output on).
  void press_now() { plant_.press_from(monotonic_ns()); }
  std::uint64_t unmodelled_mode_passes() const { return unmodelled_.load(); }
  // Where a test may change the axis's error before hapticd meets it (a fault at power-on).
  void raise_axis_error(std::uint32_t bits) { error_.fetch_or(bits); }

 private:
  void control_pass(std::int64_t now_ns);
  void send_heartbeat(std::vector<Frame>& out) const;
  Frame estimates() const;
  void command(std::uint32_t cmd, const Frame& f, std::vector<Frame>& out);

  Odrive056Config c_;
  ReferencePlant plant_;
  std::int64_t last_feed_ns_;
  std::int64_t last_heartbeat_ns_;
  std::int64_t last_encoder_ns_;
  std::atomic<std::uint8_t> state_{kIdle};
  std::atomic<std::uint32_t> error_{0};
  std::atomic<std::uint32_t> controller_error_{0};
  std::atomic<std::uint64_t> unmodelled_{0};
  std::int32_t control_mode_ = 3;  // CONTROL_MODE_POSITION_CONTROL (controller.hpp default)
  std::int32_t input_mode_ = 1;    // INPUT_MODE_PASSTHROUGH
  float input_torque_ = 0.0f;
};

}  // namespace hapticd::reference
