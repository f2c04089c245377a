// ODrive CAN Simple, pure, for firmware 0.5 (ODrive v3.x) and 0.6 (ODrive Pro, S1): frame ids
// (node << 5 | command), little-endian payloads, the heartbeat's axis error and state, and the
// error bits of each firmware. The driver and the simulated axis (sim/peers/can/) share it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "drivers/can/can_frame.h"

namespace hapticd::drivers::can::odrive {

enum class Firmware : std::uint8_t { k05, k06 };
std::string_view to_string(Firmware f) noexcept;

// Command ids (the low 5 bits of the frame id). Those marked 0.6 mean something else, or
// nothing, on 0.5.
enum Command : std::uint8_t {
  kGetVersion = 0x000,  // 0.6 (0.5: CANopen NMT)
  kHeartbeat = 0x001,
  kEstop = 0x002,
  kGetError = 0x003,  // 0.6 (0.5: Get_Motor_Error)
  kRxSdo = 0x004,     // 0.6: endpoint access
  kTxSdo = 0x005,     // 0.6: its answer
  kSetAxisState = 0x007,
  kGetEncoderEstimates = 0x009,
  kSetControllerMode = 0x00B,
  kSetInputTorque = 0x00E,
  kClearErrors = 0x018,
  kGetControllerError = 0x01D,  // 0.5.6 (Get_Controller_Error); 0.5.1-0.5.5 do not answer
};

enum AxisState : std::uint8_t {
  kAxisUndefined = 0,
  kAxisIdle = 1,
  kAxisClosedLoop = 8,
};
std::string_view axis_state_name(std::uint32_t state) noexcept;

inline constexpr std::uint32_t kControlModeTorque = 1;
inline constexpr std::uint32_t kInputModePassthrough = 1;
// The watchdog bit of each firmware's axis error (what an expired watchdog reports).
std::uint32_t watchdog_error_bit(Firmware f) noexcept;

inline constexpr std::uint32_t frame_id(std::uint8_t node, std::uint8_t command) noexcept {
  return (static_cast<std::uint32_t>(node) << 5) | command;
}
inline constexpr std::uint8_t node_of(std::uint32_t id) noexcept {
  return static_cast<std::uint8_t>((id >> 5) & 0x3F);
}
inline constexpr std::uint8_t command_of(std::uint32_t id) noexcept {
  return static_cast<std::uint8_t>(id & 0x1F);
}

// --- master -> axis ---
CanFrame set_axis_state(std::uint8_t node, std::uint32_t state) noexcept;
CanFrame set_controller_mode(std::uint8_t node, std::uint32_t control_mode,
                             std::uint32_t input_mode) noexcept;
CanFrame set_input_torque(std::uint8_t node, float torque_nm) noexcept;
CanFrame clear_errors(std::uint8_t node, Firmware f) noexcept;
// A remote request for an answer of `len` bytes (Get_Encoder_Estimates 8, Get_Version 8).
CanFrame request(std::uint8_t node, std::uint8_t command, std::uint8_t len) noexcept;
// 0.6 endpoint write (RxSdo opcode 1) and read (opcode 0) of a 32-bit value.
CanFrame rx_sdo(std::uint8_t node, bool write, std::uint16_t endpoint,
                std::uint32_t value) noexcept;

// --- axis -> master ---
struct Heartbeat {
  std::uint32_t axis_error = 0;
  std::uint8_t axis_state = 0;
  std::uint8_t flags = 0;  // 0.5: motor/encoder/controller error flags; 0.6: procedure result
};
CanFrame heartbeat(std::uint8_t node, const Heartbeat& h) noexcept;
// Needs at least the error and state (5 bytes; firmwares send 5 to 8).
std::optional<Heartbeat> decode_heartbeat(const CanFrame& f) noexcept;

struct EncoderEstimates {
  float position_turns = 0.0f;
  float velocity_turns_per_s = 0.0f;
};
CanFrame encoder_estimates(std::uint8_t node, const EncoderEstimates& e) noexcept;
std::optional<EncoderEstimates> decode_encoder_estimates(const CanFrame& f) noexcept;  // 8 bytes

struct Version {
  std::uint8_t protocol = 0;
  std::uint8_t hw_major = 0, hw_minor = 0, hw_variant = 0;
  std::uint8_t fw_major = 0, fw_minor = 0, fw_revision = 0;
};
CanFrame version_frame(std::uint8_t node, const Version& v) noexcept;
std::optional<Version> decode_version(const CanFrame& f) noexcept;  // 8 bytes
// The CAN Simple dialect of a firmware that answered Get_Version; nothing for one this
// driver does not know (0.4, 0.7...).
std::optional<Firmware> firmware_of(const Version& v) noexcept;

struct TxSdo {
  std::uint16_t endpoint = 0;
  std::uint32_t value = 0;
};
CanFrame tx_sdo(std::uint8_t node, const TxSdo& t) noexcept;
std::optional<TxSdo> decode_tx_sdo(const CanFrame& f) noexcept;  // 8 bytes
struct RxSdo {
  bool write = false;
  std::uint16_t endpoint = 0;
  std::uint32_t value = 0;
};
std::optional<RxSdo> decode_rx_sdo(const CanFrame& f) noexcept;

// 0.6's Get_Error (0x003, asked with a remote request, or sent every error_msg_rate_ms): the
// errors active now and the disarm reason, both of the ODriveError bits (ODriveArduino
// can_simple_messages.hpp, Get_Error_msg_t). A short DC-bus dip disarms the axis: by its next
// heartbeat it is IDLE with no active error, and only the disarm reason says why.
struct ErrorStatus {
  std::uint32_t active_errors = 0;
  std::uint32_t disarm_reason = 0;
};
CanFrame error_status(std::uint8_t node, const ErrorStatus& e) noexcept;
std::optional<ErrorStatus> decode_error_status(const CanFrame& f) noexcept;  // 8 bytes

// "0x00000800 WATCHDOG_TIMER_EXPIRED" (every bit set, named as the firmware names it).
std::string describe_axis_error(Firmware f, std::uint32_t axis_error);
// The axis error bit that says the controller failed and why is in controller.error (0.5
// CONTROLLER_FAILED), or that the axis ran too fast (0.6 VELOCITY_LIMIT_VIOLATION).
std::uint32_t overspeed_error_bits(Firmware f) noexcept;
// 0.5.6's answer to Get_Controller_Error: controller.error (u32); 8 bytes.
std::optional<std::uint32_t> decode_controller_error(const CanFrame& f) noexcept;
// "0x00000001 OVERSPEED" (0.5's enum Controller.Error).
std::string describe_controller_error(std::uint32_t controller_error);
inline constexpr std::uint32_t kControllerOverspeed = 0x00000001;

}  // namespace hapticd::drivers::can::odrive
