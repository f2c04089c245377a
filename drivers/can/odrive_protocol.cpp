#include "drivers/can/odrive_protocol.h"

#include <array>
#include <cstdio>

namespace hapticd::drivers::can::odrive {
namespace {

struct Bit {
  std::uint32_t bit;
  const char* name;
};

// firmware 0.5.x (ODrive v3.x), enum AxisError of odrive-interface.yaml.
constexpr std::array kErrors05 = {
    Bit{0x00000001, "INVALID_STATE"},
    Bit{0x00000040, "MOTOR_FAILED"},
    Bit{0x00000080, "SENSORLESS_ESTIMATOR_FAILED"},
    Bit{0x00000100, "ENCODER_FAILED"},
    Bit{0x00000200, "CONTROLLER_FAILED"},
    Bit{0x00000800, "WATCHDOG_TIMER_EXPIRED"},
    Bit{0x00001000, "MIN_ENDSTOP_PRESSED"},
    Bit{0x00002000, "MAX_ENDSTOP_PRESSED"},
    Bit{0x00004000, "ESTOP_REQUESTED"},
    Bit{0x00020000, "HOMING_WITHOUT_ENDSTOP"},
    Bit{0x00040000, "OVER_TEMP"},
    Bit{0x00080000, "UNKNOWN_POSITION"},
};
// firmware 0.6.x (ODrive Pro, S1), enum ODriveError: the heartbeat's axis error and Get_Error's
// active errors and disarm reason.
constexpr std::array kErrors06 = {
    Bit{0x00000001, "INITIALIZING"},
    Bit{0x00000002, "SYSTEM_LEVEL"},
    Bit{0x00000004, "TIMING_ERROR"},
    Bit{0x00000008, "MISSING_ESTIMATE"},
    Bit{0x00000010, "BAD_CONFIG"},
    Bit{0x00000020, "DRV_FAULT"},
    Bit{0x00000040, "MISSING_INPUT"},
    Bit{0x00000100, "DC_BUS_OVER_VOLTAGE"},
    Bit{0x00000200, "DC_BUS_UNDER_VOLTAGE"},
    Bit{0x00000400, "DC_BUS_OVER_CURRENT"},
    Bit{0x00000800, "DC_BUS_OVER_REGEN_CURRENT"},
    Bit{0x00001000, "CURRENT_LIMIT_VIOLATION"},
    Bit{0x00002000, "MOTOR_OVER_TEMP"},
    Bit{0x00004000, "INVERTER_OVER_TEMP"},
    Bit{0x00008000, "VELOCITY_LIMIT_VIOLATION"},
    Bit{0x00010000, "POSITION_LIMIT_VIOLATION"},
    Bit{0x01000000, "WATCHDOG_TIMER_EXPIRED"},
    Bit{0x02000000, "ESTOP_REQUESTED"},
    Bit{0x04000000, "SPINOUT_DETECTED"},
    Bit{0x08000000, "BRAKE_RESISTOR_DISARMED"},
    Bit{0x10000000, "THERMISTOR_DISCONNECTED"},
    Bit{0x40000000, "CALIBRATION_ERROR"},
};

// firmware 0.5.x, enum Controller.Error of odrive-interface.yaml (controller.error).
constexpr std::array kControllerErrors05 = {
    Bit{0x00000001, "OVERSPEED"},
    Bit{0x00000002, "INVALID_INPUT_MODE"},
    Bit{0x00000004, "UNSTABLE_GAIN"},
    Bit{0x00000008, "INVALID_MIRROR_AXIS"},
    Bit{0x00000010, "INVALID_LOAD_ENCODER"},
    Bit{0x00000020, "INVALID_ESTIMATE"},
    Bit{0x00000040, "INVALID_CIRCULAR_RANGE"},
    Bit{0x00000080, "SPINOUT_DETECTED"},
};

template <std::size_t N>
std::string name_bits(const std::array<Bit, N>& table, std::uint32_t error) {
  std::string names;
  std::uint32_t left = error;
  for (const Bit& b : table) {
    if ((error & b.bit) == 0) continue;
    names += (names.empty() ? "" : " | ") + std::string(b.name);
    left &= ~b.bit;
  }
  if (left != 0) {
    char rest[32];
    std::snprintf(rest, sizeof rest, "unknown bits 0x%08X", left);
    names += (names.empty() ? "" : " | ") + std::string(rest);
  }
  return names;
}

}  // namespace

std::string_view to_string(Firmware f) noexcept { return f == Firmware::k05 ? "0.5" : "0.6"; }

std::string_view axis_state_name(std::uint32_t state) noexcept {
  static constexpr std::array<std::string_view, 15> kNames = {
      "UNDEFINED",
      "IDLE",
      "STARTUP_SEQUENCE",
      "FULL_CALIBRATION_SEQUENCE",
      "MOTOR_CALIBRATION",
      "SENSORLESS_CONTROL (0.5)",
      "ENCODER_INDEX_SEARCH",
      "ENCODER_OFFSET_CALIBRATION",
      "CLOSED_LOOP_CONTROL",
      "LOCKIN_SPIN",
      "ENCODER_DIR_FIND",
      "HOMING",
      "ENCODER_HALL_POLARITY_CALIBRATION",
      "ENCODER_HALL_PHASE_CALIBRATION",
      "ANTICOGGING_CALIBRATION (0.6)",
  };
  return state < kNames.size() ? kNames[state] : "an axis state this driver does not know";
}

std::uint32_t watchdog_error_bit(Firmware f) noexcept {
  return f == Firmware::k05 ? 0x00000800u : 0x01000000u;
}

CanFrame set_axis_state(std::uint8_t node, std::uint32_t state) noexcept {
  CanFrame f = make_frame(frame_id(node, kSetAxisState), 4);
  put_u32(f, 0, state);
  return f;
}

CanFrame set_controller_mode(std::uint8_t node, std::uint32_t control_mode,
                             std::uint32_t input_mode) noexcept {
  CanFrame f = make_frame(frame_id(node, kSetControllerMode), 8);
  put_u32(f, 0, control_mode);
  put_u32(f, 4, input_mode);
  return f;
}

CanFrame set_input_torque(std::uint8_t node, float torque_nm) noexcept {
  CanFrame f = make_frame(frame_id(node, kSetInputTorque), 4);
  put_f32(f, 0, torque_nm);
  return f;
}

CanFrame clear_errors(std::uint8_t node, Firmware fw) noexcept {
  // 0.6 takes an "identify" byte (0: do not blink the LED); 0.5 takes nothing.
  return make_frame(frame_id(node, kClearErrors), fw == Firmware::k06 ? 1 : 0);
}

CanFrame request(std::uint8_t node, std::uint8_t command, std::uint8_t len) noexcept {
  CanFrame f = make_frame(frame_id(node, command), len);
  f.rtr = true;
  return f;
}

CanFrame rx_sdo(std::uint8_t node, bool write, std::uint16_t endpoint,
                std::uint32_t value) noexcept {
  CanFrame f = make_frame(frame_id(node, kRxSdo), 8);
  f.data[0] = write ? 1 : 0;
  put_u16(f, 1, endpoint);
  put_u32(f, 4, value);
  return f;
}

CanFrame heartbeat(std::uint8_t node, const Heartbeat& h) noexcept {
  CanFrame f = make_frame(frame_id(node, kHeartbeat), 8);
  put_u32(f, 0, h.axis_error);
  f.data[4] = h.axis_state;
  f.data[5] = h.flags;
  return f;
}

std::optional<Heartbeat> decode_heartbeat(const CanFrame& f) noexcept {
  if (f.rtr || f.len < 5) return std::nullopt;
  return Heartbeat{get_u32(f, 0), f.data[4], f.len > 5 ? f.data[5] : std::uint8_t{0}};
}

CanFrame encoder_estimates(std::uint8_t node, const EncoderEstimates& e) noexcept {
  CanFrame f = make_frame(frame_id(node, kGetEncoderEstimates), 8);
  put_f32(f, 0, e.position_turns);
  put_f32(f, 4, e.velocity_turns_per_s);
  return f;
}

std::optional<EncoderEstimates> decode_encoder_estimates(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 8) return std::nullopt;
  return EncoderEstimates{get_f32(f, 0), get_f32(f, 4)};
}

CanFrame version_frame(std::uint8_t node, const Version& v) noexcept {
  CanFrame f = make_frame(frame_id(node, kGetVersion), 8);
  f.data = {v.protocol, v.hw_major, v.hw_minor,    v.hw_variant,
            v.fw_major, v.fw_minor, v.fw_revision, 0};
  return f;
}

std::optional<Version> decode_version(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 8) return std::nullopt;
  return Version{f.data[0], f.data[1], f.data[2], f.data[3], f.data[4], f.data[5], f.data[6]};
}

std::optional<Firmware> firmware_of(const Version& v) noexcept {
  if (v.fw_major != 0) return std::nullopt;
  if (v.fw_minor == 5) return Firmware::k05;
  if (v.fw_minor == 6) return Firmware::k06;
  return std::nullopt;
}

CanFrame tx_sdo(std::uint8_t node, const TxSdo& t) noexcept {
  CanFrame f = make_frame(frame_id(node, kTxSdo), 8);
  put_u16(f, 1, t.endpoint);
  put_u32(f, 4, t.value);
  return f;
}

std::optional<TxSdo> decode_tx_sdo(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 8) return std::nullopt;
  return TxSdo{get_u16(f, 1), get_u32(f, 4)};
}

std::optional<RxSdo> decode_rx_sdo(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 8 || f.data[0] > 1) return std::nullopt;
  return RxSdo{f.data[0] == 1, get_u16(f, 1), get_u32(f, 4)};
}

CanFrame error_status(std::uint8_t node, const ErrorStatus& e) noexcept {
  CanFrame f = make_frame(frame_id(node, kGetError), 8);
  put_u32(f, 0, e.active_errors);
  put_u32(f, 4, e.disarm_reason);
  return f;
}

std::optional<ErrorStatus> decode_error_status(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 8) return std::nullopt;
  return ErrorStatus{get_u32(f, 0), get_u32(f, 4)};
}

std::string describe_axis_error(Firmware f, std::uint32_t axis_error) {
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%08X", axis_error);
  if (axis_error == 0) return std::string(hex) + " (no error)";
  return std::string(hex) + " " +
         (f == Firmware::k05 ? name_bits(kErrors05, axis_error) : name_bits(kErrors06, axis_error));
}

std::uint32_t overspeed_error_bits(Firmware f) noexcept {
  return f == Firmware::k05 ? 0x00000200u : 0x00008000u;
}

std::optional<std::uint32_t> decode_controller_error(const CanFrame& f) noexcept {
  if (f.rtr || f.len != 8) return std::nullopt;
  return get_u32(f, 0);
}

std::string describe_controller_error(std::uint32_t controller_error) {
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%08X", controller_error);
  if (controller_error == 0) return std::string(hex) + " (no error)";
  return std::string(hex) + " " + name_bits(kControllerErrors05, controller_error);
}

}  // namespace hapticd::drivers::can::odrive
