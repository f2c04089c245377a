#include "drivers/can/cia402.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hapticd::drivers::can::cia402 {
namespace {

// Statusword bits (CiA 402 §6.2).
constexpr std::uint16_t kSwWarning = 1u << 7;
constexpr std::uint16_t kSwRemote = 1u << 9;
constexpr std::uint16_t kSwTargetReached = 1u << 10;
constexpr std::uint16_t kSwInternalLimit = 1u << 11;

// Controlword commands are recognised by their significant bits (CiA 402 Table 29).
bool is_shutdown(std::uint16_t cw) { return (cw & 0x87) == 0x06; }
bool is_switch_on(std::uint16_t cw) { return (cw & 0x8F) == 0x07; }
bool is_enable_operation(std::uint16_t cw) { return (cw & 0x8F) == 0x0F; }
bool is_disable_voltage(std::uint16_t cw) { return (cw & 0x82) == 0x00; }
bool is_quick_stop(std::uint16_t cw) { return (cw & 0x86) == 0x02; }

MappingEntry entry(std::uint16_t index, std::uint8_t sub, std::uint32_t value, std::uint8_t size,
                   bool final) {
  return {{index, sub}, value, size, final, false};
}
MappingEntry cob_id(std::uint16_t index, std::uint32_t value, bool final) {
  return {{index, 1}, value, 4, final, true};
}

// One PDO: invalidate, transmission type, clear mapping, entries, count, validate.
void add_pdo(std::vector<MappingEntry>& out, std::uint16_t comm, std::uint16_t map,
             std::uint32_t id, std::initializer_list<std::uint32_t> objects) {
  out.push_back(cob_id(comm, kCobIdInvalid | id, false));
  out.push_back(entry(comm, 2, 1, 1, true));  // synchronous, every SYNC
  out.push_back(entry(map, 0, 0, 1, false));
  std::uint8_t sub = 1;
  for (const std::uint32_t object : objects) out.push_back(entry(map, sub++, object, 4, true));
  out.push_back(entry(map, 0, static_cast<std::uint32_t>(objects.size()), 1, true));
  out.push_back(cob_id(comm, id, true));
}

}  // namespace

std::string_view to_string(PowerState s) noexcept {
  switch (s) {
    case PowerState::kNotReadyToSwitchOn:
      return "not ready to switch on";
    case PowerState::kSwitchOnDisabled:
      return "switch on disabled";
    case PowerState::kReadyToSwitchOn:
      return "ready to switch on";
    case PowerState::kSwitchedOn:
      return "switched on";
    case PowerState::kOperationEnabled:
      return "operation enabled";
    case PowerState::kQuickStopActive:
      return "quick stop active";
    case PowerState::kFaultReactionActive:
      return "fault reaction active";
    case PowerState::kFault:
      return "fault";
  }
  return "unknown";
}

PowerState decode_statusword(std::uint16_t sw) noexcept {
  switch (sw & 0x4F) {
    case 0x00:
      return PowerState::kNotReadyToSwitchOn;
    case 0x40:
      return PowerState::kSwitchOnDisabled;
    case 0x08:
      return PowerState::kFault;
    case 0x0F:
      return PowerState::kFaultReactionActive;
    default:
      break;
  }
  switch (sw & 0x6F) {
    case 0x21:
      return PowerState::kReadyToSwitchOn;
    case 0x23:
      return PowerState::kSwitchedOn;
    case 0x27:
      return PowerState::kOperationEnabled;
    case 0x07:
      return PowerState::kQuickStopActive;
    default:
      return PowerState::kNotReadyToSwitchOn;  // a combination 402 does not define
  }
}

std::uint16_t encode_statusword(PowerState s, bool warning) noexcept {
  std::uint16_t sw = kSwRemote | (warning ? kSwWarning : 0);
  switch (s) {
    case PowerState::kNotReadyToSwitchOn:
      return sw;
    case PowerState::kSwitchOnDisabled:
      return sw | 0x40;
    case PowerState::kReadyToSwitchOn:
      return sw | 0x21;
    case PowerState::kSwitchedOn:
      return sw | 0x23 | kSwVoltageEnabled;
    case PowerState::kOperationEnabled:
      return sw | 0x27 | kSwVoltageEnabled;
    case PowerState::kQuickStopActive:
      return sw | 0x07 | kSwVoltageEnabled;
    case PowerState::kFaultReactionActive:
      return sw | 0x0F;
    case PowerState::kFault:
      return sw | 0x08;
  }
  return sw;
}

std::string describe_statusword(std::uint16_t sw) {
  char head[16];
  std::snprintf(head, sizeof head, "0x%04X ", sw);
  std::string text = head + std::string(to_string(decode_statusword(sw)));
  if (sw & kSwWarning) text += ", warning";
  if (sw & kSwRemote) text += ", remote";
  if (sw & kSwTargetReached) text += ", target reached";
  if (sw & kSwInternalLimit) text += ", internal limit active";
  return text;
}

std::optional<std::uint16_t> step_towards_enabled(PowerState s) noexcept {
  switch (s) {
    case PowerState::kSwitchOnDisabled:
      return kCwShutdown;
    case PowerState::kReadyToSwitchOn:
      return kCwSwitchOn;
    case PowerState::kSwitchedOn:
      return kCwEnableOperation;
    case PowerState::kQuickStopActive:
      return kCwDisableVoltage;  // back to switch on disabled, then up again
    default:
      return std::nullopt;
  }
}

PowerState apply_controlword(PowerState s, std::uint16_t cw, std::uint16_t previous) noexcept {
  switch (s) {
    case PowerState::kFault:
      return (cw & kCwFaultReset) != 0 && (previous & kCwFaultReset) == 0
                 ? PowerState::kSwitchOnDisabled
                 : s;
    case PowerState::kNotReadyToSwitchOn:
    case PowerState::kFaultReactionActive:
      return s;  // the drive moves on by itself
    default:
      break;
  }
  if (is_disable_voltage(cw)) return PowerState::kSwitchOnDisabled;
  if (is_quick_stop(cw)) {
    return s == PowerState::kOperationEnabled ? PowerState::kQuickStopActive
                                              : PowerState::kSwitchOnDisabled;
  }
  if (s == PowerState::kQuickStopActive) return s;  // only disable voltage leaves it here
  if (is_shutdown(cw)) return PowerState::kReadyToSwitchOn;
  if (is_switch_on(cw)) {
    return s == PowerState::kSwitchOnDisabled ? s : PowerState::kSwitchedOn;
  }
  if (is_enable_operation(cw)) {
    return s == PowerState::kSwitchedOn || s == PowerState::kOperationEnabled
               ? PowerState::kOperationEnabled
               : s;
  }
  return s;
}

std::vector<MappingEntry> pdo_mapping(std::uint8_t node, bool with_velocity) {
  std::vector<MappingEntry> out;
  add_pdo(out, 0x1400, 0x1600, canopen::kRpdo1Base + node, {0x60400010, 0x60710010});
  add_pdo(out, 0x1800, 0x1A00, canopen::kTpdo1Base + node, {0x60410010, 0x60640020});
  if (with_velocity) {
    add_pdo(out, 0x1801, 0x1A01, canopen::kTpdo2Base + node, {0x606C0020});
  } else {
    out.push_back(cob_id(0x1801, kCobIdInvalid | (canopen::kTpdo2Base + node), true));
  }
  // The other default PDOs (RPDO2-4, TPDO3-4) stay off the bus.
  for (std::uint16_t i = 1; i < 4; ++i) {
    out.push_back(cob_id(static_cast<std::uint16_t>(0x1400 + i),
                         kCobIdInvalid | (canopen::kRpdo1Base + 0x100u * i + node), true));
  }
  for (std::uint16_t i = 2; i < 4; ++i) {
    out.push_back(cob_id(static_cast<std::uint16_t>(0x1800 + i),
                         kCobIdInvalid | (canopen::kTpdo1Base + 0x100u * i + node), true));
  }
  return out;
}

InterpolationPeriod interpolation_period(double period_s) noexcept {
  // The largest power of ten that gives a whole value up to 255 (1 ms: 1 x 10^-3).
  InterpolationPeriod best{255, -6, false};
  double best_error = 1e300;
  for (int index = 0; index >= -6; --index) {
    const double unit = std::pow(10.0, index);
    const double value = std::round(period_s / unit);
    if (value < 1.0 || value > 255.0) continue;
    const double error = std::abs(value * unit - period_s);
    if (error <= 1e-12 * std::max(1.0, period_s / unit)) {
      return {static_cast<std::uint8_t>(value), static_cast<std::int8_t>(index), true};
    }
    if (error < best_error) {
      best_error = error;
      best = {static_cast<std::uint8_t>(value), static_cast<std::int8_t>(index), false};
    }
  }
  return best;
}

}  // namespace hapticd::drivers::can::cia402
