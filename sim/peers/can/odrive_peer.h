// A simulated ODrive axis speaking CAN Simple (firmware 0.5 or 0.6, as configured; "auto"
// simulates 0.6, which answers Get_Version): axis states IDLE and CLOSED_LOOP_CONTROL, torque
// control with passthrough input, Get_Encoder_Estimates answered to each remote request (or
// sent cyclically, one per torque command at the configured period), heartbeats with the axis
// error and state, Clear_Errors, 0.6 endpoint access (RxSdo/TxSdo) and the axis watchdog: in
// realtime, no frame for watchdog_timeout_s in closed loop is WATCHDOG_TIMER_EXPIRED and IDLE,
// which is what keeps a real axis safe when hapticd is killed.
//
// The plant steps one period per trigger (the encoder request, or in cyclic mode the torque
// command): the torque sent just before a trigger acts from it on, for the next period.
#pragma once

#include <cstdint>
#include <map>

#include "drivers/can/odrive_protocol.h"
#include "sim/peers/can/can_peer_base.h"

namespace hapticd::sim {

class OdrivePeer final : public CanPeerBase {
 public:
  // `joint`: the joint of a mechanism it moves with the other drives of its bus (can_bus_peer.h).
  OdrivePeer(const config::Config& cfg, drivers::can::CanSocket socket, bool realtime,
             const SharedJoint& joint = {});
  // The axis error a commanded fault raises (0.5 MOTOR_FAILED, 0.6 CURRENT_LIMIT_VIOLATION).
  std::uint32_t fault_error() const noexcept;
  // Any thread, for tests.
  std::uint8_t axis_state() const noexcept { return state_.load(); }
  // Any thread, for tests: remote requests for Get_Error (0x003) received (0.6 answers them).
  int error_requests() const noexcept { return error_requests_.load(); }
  // 0.6's DC_BUS_UNDER_VOLTAGE: the disarm reason CanPeerFault::kDisarm leaves.
  static constexpr std::uint32_t kDcBusUnderVoltage = 0x00000200;

 protected:
  void handle(const drivers::can::CanFrame& f) override;
  void on_clock(std::int64_t now_ns) override;
  void apply_device_fault() override;
  void on_bus_lost() override;

 private:
  void set_state(std::uint8_t state);
  void trigger();
  void send_heartbeat();
  void on_command(std::uint8_t command, const drivers::can::CanFrame& f);
  // 0.6: an error disarms the axis and stays in the disarm reason until Clear_Errors.
  void disarm(std::uint32_t reason, bool stays_active);
  void take_disarm();

  const std::uint8_t node_;
  const drivers::can::odrive::Firmware firmware_;
  std::atomic<std::uint8_t> state_{drivers::can::odrive::kAxisIdle};
  std::uint32_t axis_error_ = 0;     // the heartbeat's: 0.6's active errors
  std::uint32_t disarm_reason_ = 0;  // 0.6
  std::atomic<int> error_requests_{0};
  std::uint32_t control_mode_ = 3;  // position control, the firmware's default
  std::uint32_t input_mode_ = 1;
  float input_torque_ = 0.0f;
  bool stepped_ = false;
  std::uint64_t triggers_ = 0;
  std::map<std::uint16_t, std::uint32_t> endpoints_;
  double watchdog_timeout_s_;
  std::int64_t last_frame_ns_ = 0;
  std::int64_t last_heartbeat_ns_ = 0;
};

}  // namespace hapticd::sim
