// ODrive axes (OdriveAxis, one per node of device.can.nodes; OdriveProfile drives them all on
// one bus), each in closed-loop torque control with passthrough input, over CAN Simple
// (docs/drivers/can.md), firmware 0.5 or 0.6 (configured, or detected: 0.6 answers Get_Version).
//
// configure: the axis watchdog fed from here on (0.5 runs it in every axis state: an axis
// nobody talked to since power-on reports WATCHDOG_TIMER_EXPIRED), the firmware found, a
// heartbeat awaited - exactly WATCHDOG_TIMER_EXPIRED is cleared (Clear_Errors), any other axis
// error refuses - the axis put in IDLE (output off) with torque control + passthrough, and on
// 0.6, where endpoint ids are configured, the axis watchdog enabled and its time-out written
// and read back. Estimates the axis sends by itself are noticed.
// enable: input torque 0, CLOSED_LOOP_CONTROL requested and confirmed by a heartbeat within
// state_timeout_ms; then the loop's own frames feed the watchdog.
// Each tick: the device drains encoder estimates, heartbeats and bus events; the tick's frames
// are Set_Input_Torque (N m, through the transmission) and, in request mode, the remote
// request for Get_Encoder_Estimates, whose answer (the first estimate after it: cyclic ones in
// between are not samples of this tick) is the position the next tick acts on; the torque
// acts from now until the next write: one sample of delay (cyclic mode: the message period in
// samples, at least one).
// A 0.6 axis that leaves closed loop by itself (or reports an error) is asked why: the RT path
// latches the fault and sends the remote request for Get_Error with the tick's zero torque,
// never waiting; the answer (its disarm reason) is taken by disable, which waits for it up to
// sdo_timeout_ms, and named by describe.
// disable: torque 0, IDLE, once however often it is asked, and the watchdog fed again.
// clear_fault: Clear_Errors, confirmed by a heartbeat without error.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/joints.h"
#include "drivers/can/can_profile.h"
#include "drivers/can/odrive_protocol.h"
#include "drivers/can/periodic_sender.h"

namespace hapticd::drivers::can {

// One axis (node id) on the bus, with its own CAN Simple ids, watchdog feeder and
// request-mode position requests. OdriveProfile drives the axes of device.can.nodes.
class OdriveAxis {
 public:
  OdriveAxis(const CanSettings& settings, const CanNode& node, double sample_period_s,
             CanLink& link)
      : settings_(settings),
        node_(node),
        period_s_(sample_period_s),
        link_(link),
        firmware_(settings.odrive.firmware),
        id_base_(odrive::frame_id(node.node_id, 0)) {}
  OdriveAxis(const OdriveAxis&) = delete;
  OdriveAxis& operator=(const OdriveAxis&) = delete;

  DeviceInfo configure();
  void enable();
  // The stop in two steps, so every axis is given zero torque before any is asked why it
  // stopped: zero torque and IDLE (once per enable; true when they went out now), then what
  // explains `latched` (this axis's fault, or none) and the watchdog fed again.
  bool stop_output() noexcept;
  void after_stop(const CanFault& latched, bool stopped_now) noexcept;
  void clear_fault();
  void close() noexcept { feeder_.stop(); }
  // After every axis is enabled: from here only the loop feeds the watchdog (if it stops, the
  // axis stops).
  void stop_feeding() noexcept { feeder_.stop(); }
  const std::vector<std::string>& notices() const { return notices_; }
  // What emergency_stop() writes for this axis: Set_Input_Torque 0, Set_Axis_State IDLE.
  std::array<CanFrame, 2> emergency_frames() const noexcept;
  // RT-safe: called every tick (the four below). Whether a frame is this axis's.
  bool owns(const CanFrame& f) const noexcept {
    return !f.extended && !f.rtr && (f.id & ~0x1Fu) == id_base_;
  }
  FrameMeaning on_frame(const CanSocket::Received& rx, bool active) noexcept;
  void sample(PositionSample& out) const noexcept;
  std::span<const CanFrame> tick_frames(double force) noexcept;
  // Not RT-safe. The sentence for a fault this axis reported; "" for the bus's.
  std::string describe(const CanFault& fault, const std::string& bus) const;

 private:
  // RT-safe: called every tick (on_frame's parts).
  FrameMeaning on_estimates(const CanSocket::Received& rx) noexcept;
  FrameMeaning on_heartbeat(const CanFrame& f, bool active) noexcept;
  std::string detect_firmware();
  // The next heartbeat within timeout_ms for which `accept` holds; throws naming `waiting_for`.
  odrive::Heartbeat await_heartbeat(int timeout_ms, const std::string& waiting_for,
                                    bool (*accept)(const odrive::Heartbeat&));
  void configure_watchdog();
  // Exactly WATCHDOG_TIMER_EXPIRED: cleared and confirmed; any other error refuses.
  odrive::Heartbeat clear_expired_watchdog(odrive::Heartbeat h);
  void feed_watchdog();
  void note_unsolicited(const CanFrame& f);
  void read_controller_error(const CanFault& latched) noexcept;
  void read_error_status(const CanFault& latched) noexcept;
  void forget_error_status() noexcept {
    error_request_due_ = false;
    error_requested_ = false;
    error_status_.reset();
  }
  std::string disarm_text(const CanFault& fault) const;
  std::string overspeed_text(std::uint32_t axis_error) const;
  std::string node_name(const std::string& bus) const;
  std::string node_name() const { return node_name(link_.description()); }

  const CanSettings& settings_;  // the bus's (the profile's, which outlives its axes)
  const CanNode node_;
  const double period_s_;
  CanLink& link_;
  std::vector<std::string> notices_;  // configure's
  odrive::Firmware firmware_;
  const std::uint32_t id_base_;  // node << 5
  PeriodicSender feeder_;
  bool stopped_ = true;            // the disable frames went out since the last enable
  int unsolicited_estimates_ = 0;  // seen while configuring (request mode)
  std::optional<std::uint32_t> controller_error_;  // 0.5.6's answer after CONTROLLER_FAILED
  std::array<CanFrame, 3> tx_{};                   // the tick's frames
  // 0.6's Get_Error after the axis disarmed: due from the RT path (sent with the next tick's
  // frames), sent, and its answer (taken by a read or by disable).
  bool error_request_due_ = false;
  bool error_requested_ = false;
  std::optional<odrive::ErrorStatus> error_status_;

  // RT state of the newest sample.
  float position_turns_ = 0.0f;
  float velocity_turns_ = 0.0f;
  std::int64_t sample_time_ns_ = 0;
  std::uint8_t axis_state_ = 0;
  std::int64_t request_ns_ = 0;    // when this tick's Get_Encoder_Estimates request went out
  bool answered_ = true;           // the answer to it arrived
  float last_speed_turns_ = 0.0f;  // the newest estimate's, for a fault's description
};

// The axes of device.can.nodes on one bus, joint i being axis i: each tick every axis's
// frames; the lifecycle through every axis (a fault of any axis is the device's: the loop
// writes zero to every joint, and the stop idles every axis).
class OdriveProfile final : public CanProfile {
 public:
  OdriveProfile(const CanSettings& settings, double sample_period_s, CanLink& link);

  DeviceInfo configure() override;
  void enable() override;
  void disable(const CanFault& latched) noexcept override;
  void clear_fault() override;
  void close() noexcept override;
  std::vector<std::string> notices() const override;
  // RT-safe: called every tick (the three below).
  FrameMeaning on_frame(const CanSocket::Received& rx, bool active) noexcept override;
  void sample(std::size_t joint, PositionSample& out) const noexcept override;
  std::span<const CanFrame> tick_frames(std::span<const double> forces) noexcept override;
  std::string describe(const CanFault& fault, const std::string& bus) const override;

 private:
  const CanSettings settings_;
  CanLink& link_;
  std::vector<std::unique_ptr<OdriveAxis>> axes_;    // built once (the RT path indexes it)
  std::array<CanFrame, 3 * base::kMaxJoints> tx_{};  // the tick's frames
};

}  // namespace hapticd::drivers::can
