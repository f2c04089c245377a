// An ODrive Pro / S1 axis as firmware 0.6 behaves on CAN Simple, sharing nothing with drivers/.
// The 0.6 firmware's source is not public; this follows what ODrive publishes for it:
//
// - ODriveArduino v0.10.9 (github odriverobotics/ODriveArduino, tag v0.10.9 = 366b780; the
//   files below are the same at f52eef5, its newest commit),
//   src/can_simple_messages.hpp (generated from the firmware's DBC): the command ids and
//   layouts - Get_Version 0x000 (protocol, hw major/minor/variant, fw major/minor/revision,
//   unreleased: one byte each), Heartbeat 0x001 (Axis_Error u32, Axis_State u8,
//   Procedure_Result u8, Trajectory_Done_Flag bit 48), Estop 0x002, Get_Error 0x003
//   (Active_Errors u32, Disarm_Reason u32), Set_Axis_State 0x007 (u32),
//   Get_Encoder_Estimates 0x009 (Pos_Estimate, Vel_Estimate: float rev, rev/s),
//   Set_Controller_Mode 0x00B (Control_Mode u32, Input_Mode u32), Set_Input_Torque 0x00E
//   (float N m), Clear_Errors 0x018 (Identify u8); all little-endian. src/ODriveCAN.h/.cpp:
//   getError(), getVersion() and getFeedback() are remote requests (request(): RTR, no data),
//   answered with the message of the same id.
// - ODriveArduino v0.10.9 src/ODriveEnums.h: ODriveAxisState (IDLE 1, CLOSED_LOOP_CONTROL 8),
//   ODriveControlMode (TORQUE_CONTROL 1), ODriveInputMode (PASSTHROUGH 1), ODriveError (the
//   bits of Axis_Error, Active_Errors and Disarm_Reason: DC_BUS_UNDER_VOLTAGE 0x200,
//   ESTOP_REQUESTED 0x02000000, ...): the enums of firmware 0.6 as that tag carries them
//   (ODriveError unchanged since the library's first commit, 91afc00, 2023-07-13; the CAN
//   DBC of firmware 0.6.10, odrive-cansimple-0.6.10, lists the same Axis_Error bits). The
//   Get_Version answer below says 0.6.10.
// - ros_odrive (github odriverobotics/ros_odrive, commit 8ed510b), odrive_node/src/
//   odrive_can_node.cpp, recv_callback: the heartbeat's first u32 is the axis's active errors;
//   Get_Error carries active_errors then disarm_reason.
// - ODrive documentation, "Error/Enable" (docs.odriverobotics.com/v/latest/manual/
//   error-enable.html): an error status is any flag "in active_errors or disarm_reason", and
//   "can be cleared by removing the error condition and calling clear_errors()".
//
// A disarm: an error while the axis is armed (CLOSED_LOOP_CONTROL) ends closed loop - IDLE,
// no torque - and is kept in the disarm reason until Clear_Errors. An active error lasts only
// as long as its condition: a DC-bus dip shorter than the heartbeat period is over before the
// next heartbeat, which then says IDLE with no active error (issue 34: ODrive Pro and S1 on
// 0.6.x). Closed loop is refused while an error is active.
//
// Not modelled: the axis watchdog, the torque-mode velocity limit (hapticd's configuration
// sets device.can.odrive.vel_limit 0 against this axis), endpoints (RxSdo), position and
// velocity control (counted as unmodelled passes), the procedure result (always SUCCESS here).
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "reference/can/can_wire.h"
#include "reference/can/reference_plant.h"
#include "reference/can/reference_runner.h"

namespace hapticd::reference {

struct Odrive06Config {
  std::uint8_t node = 1;
  std::uint32_t heartbeat_msg_rate_ms = 100;  // axis.config.can.heartbeat_msg_rate_ms
  std::uint32_t encoder_msg_rate_ms = 10;     // axis.config.can.encoder_msg_rate_ms
  std::uint32_t error_msg_rate_ms = 0;        // axis.config.can.error_msg_rate_ms; 0: on request
  // The axis behind the motor: metres per motor turn, and the motor torque per axis newton.
  double metres_per_turn = 0.09817477042468103;
  double nm_per_newton = 0.015625;
  // Get_Version's answer (hapticd takes the dialect from the firmware fields).
  std::uint8_t fw_major = 0, fw_minor = 6, fw_revision = 10;
};

class Odrive06 final : public ReferenceDevice {
 public:
  // ODriveEnums.h
  static constexpr std::uint8_t kIdle = 1;
  static constexpr std::uint8_t kClosedLoop = 8;
  static constexpr std::uint32_t kDcBusUnderVoltage = 0x00000200;
  static constexpr std::uint32_t kEstopRequested = 0x02000000;

  Odrive06(const Odrive06Config& c, const PlantParameters& plant, std::int64_t now_ns);

  void on_frame(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) override;
  void on_clock(std::int64_t now_ns, std::vector<Frame>& out) override;

  // Any thread.
  std::uint8_t state() const { return state_.load(); }
  bool armed() const { return state() == kClosedLoop; }
  std::uint32_t active_errors() const { return active_.load(); }
  std::uint32_t disarm_reason() const { return disarm_reason_.load(); }
  double position_m() const { return plant_.position_now(); }
  double motor_force_n() const { return plant_.motor_force_now(); }
  void press_now() { plant_.press_from(monotonic_ns()); }
  // Remote requests for Get_Error answered so far.
  int error_requests() const { return error_requests_.load(); }
  std::uint64_t unmodelled_mode_passes() const { return unmodelled_.load(); }
  // The DC bus dips below the under-voltage trip level for `ms`, starting just after the next
  // cyclic heartbeat (so that one shorter than the heartbeat period is over by the one after):
  // DC_BUS_UNDER_VOLTAGE is active meanwhile, and disarms the axis if armed.
  void dip_dc_bus(int ms) { dip_ms_.store(ms); }

 private:
  void control_pass(std::int64_t now_ns);
  void command(std::uint32_t cmd, const Frame& f, std::vector<Frame>& out);
  void request(std::uint32_t cmd, std::vector<Frame>& out);
  Frame heartbeat() const;
  Frame estimates() const;
  Frame error_message() const;
  Frame message(std::uint32_t cmd) const;

  Odrive06Config c_;
  ReferencePlant plant_;
  std::atomic<std::uint8_t> state_{kIdle};
  std::atomic<std::uint32_t> active_{0};         // errors whose condition is present now
  std::atomic<std::uint32_t> disarm_reason_{0};  // what disarmed the axis, until Clear_Errors
  std::uint32_t latched_ = 0;                    // errors raised by a command (Estop)
  std::atomic<int> dip_ms_{0};                   // a dip to begin after the next heartbeat
  std::int64_t dip_until_ns_ = 0;
  std::atomic<int> error_requests_{0};
  std::atomic<std::uint64_t> unmodelled_{0};
  std::uint32_t control_mode_ = 3;  // POSITION_CONTROL
  std::uint32_t input_mode_ = 1;    // PASSTHROUGH
  float input_torque_ = 0.0f;
  std::int64_t last_heartbeat_ns_;
  std::int64_t last_encoder_ns_;
  std::int64_t last_error_ns_;
};

}  // namespace hapticd::reference
