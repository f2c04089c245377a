// CiA 402 (drives and motion control) as hapticd uses it, pure: the objects, the power state
// machine seen from both ends (the statusword a drive reports, the controlword that moves it
// on, and - for the simulated drive - how a controlword moves a state), and the PDO mapping
// of cyclic synchronous torque that the driver configures or verifies (DESIGN.md §6).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/can/canopen.h"

namespace hapticd::drivers::can::cia402 {

// Objects (index, subindex) hapticd reads or writes.
inline constexpr canopen::SdoAddress kDeviceType{0x1000, 0};
inline constexpr canopen::SdoAddress kErrorRegister{0x1001, 0};
inline constexpr canopen::SdoAddress kCommunicationCyclePeriod{0x1006, 0};  // us
inline constexpr canopen::SdoAddress kConsumerHeartbeatTime{0x1016, 1};     // node << 16 | ms
inline constexpr canopen::SdoAddress kProducerHeartbeatTime{0x1017, 0};     // ms
inline constexpr canopen::SdoAddress kVendorId{0x1018, 1};
inline constexpr canopen::SdoAddress kAbortConnectionOption{0x6007, 0};
inline constexpr canopen::SdoAddress kErrorCode{0x603F, 0};
inline constexpr canopen::SdoAddress kControlword{0x6040, 0};
inline constexpr canopen::SdoAddress kStatusword{0x6041, 0};
inline constexpr canopen::SdoAddress kModesOfOperation{0x6060, 0};
inline constexpr canopen::SdoAddress kModesOfOperationDisplay{0x6061, 0};
inline constexpr canopen::SdoAddress kTargetTorque{0x6071, 0};
inline constexpr canopen::SdoAddress kRatedTorque{0x6076, 0};  // mN m
inline constexpr canopen::SdoAddress kPositionActual{0x6064, 0};
inline constexpr canopen::SdoAddress kVelocityActual{0x606C, 0};

inline constexpr std::uint16_t kDeviceProfile402 = 402;  // low 16 bits of 0x1000
inline constexpr std::int8_t kModeCyclicSynchronousTorque = 10;

// Controlword commands (the bits that matter; DESIGN.md §6).
inline constexpr std::uint16_t kCwDisableVoltage = 0x00;
inline constexpr std::uint16_t kCwQuickStop = 0x02;
inline constexpr std::uint16_t kCwShutdown = 0x06;
inline constexpr std::uint16_t kCwSwitchOn = 0x07;  // also "disable operation" when enabled
inline constexpr std::uint16_t kCwEnableOperation = 0x0F;
inline constexpr std::uint16_t kCwFaultReset = 0x80;

// 0x6007 abort connection option code: what the drive does when it loses the master (heartbeat
// consumer time-out, bus-off, SYNC loss where the drive watches 0x1006).
enum class CommLossReaction : std::uint8_t {
  kNone = 0,
  kFault = 1,
  kDisableVoltage = 2,
  kQuickStop = 3,
};

enum class PowerState : std::uint8_t {
  kNotReadyToSwitchOn,
  kSwitchOnDisabled,
  kReadyToSwitchOn,
  kSwitchedOn,
  kOperationEnabled,
  kQuickStopActive,
  kFaultReactionActive,
  kFault,
};
std::string_view to_string(PowerState s) noexcept;

// The state a statusword reports (mask 0x4F / 0x6F).
PowerState decode_statusword(std::uint16_t statusword) noexcept;
// The statusword a drive in `s` reports (remote bit set, warning bit from `warning`).
std::uint16_t encode_statusword(PowerState s, bool warning = false) noexcept;
// "0x0627 operation enabled, remote, target reached".
std::string describe_statusword(std::uint16_t statusword);
// The controlword that moves `s` one step towards Operation enabled; nothing from Fault (it
// needs a fault reset first), from Not ready to switch on (the drive moves on by itself) and
// from Operation enabled itself.
std::optional<std::uint16_t> step_towards_enabled(PowerState s) noexcept;
// The drive's side: the state after controlword `cw` arrives in `s`, given the previous
// controlword (a fault reset is its bit 7's rising edge).
PowerState apply_controlword(PowerState s, std::uint16_t cw, std::uint16_t previous_cw) noexcept;
// Whether the power stage produces torque in `s`.
inline bool torque_enabled(PowerState s) noexcept {
  return s == PowerState::kOperationEnabled || s == PowerState::kQuickStopActive;
}

// --- the PDO mapping (configured with pdo_mapping: configure, compared with: verify) ---
struct MappingEntry {
  canopen::SdoAddress at;
  std::uint32_t value;
  std::uint8_t size;
  bool final;  // the value the object must end with (verify reads these back); false for the
               // intermediate writes (PDO invalidated, mapping count 0) of the procedure
};
// In write order (CiA 301 §7.5.2.36): each PDO is invalidated, its transmission type set (1:
// every SYNC), its mapping count set to 0, the entries written, the count written, and the PDO
// made valid again. The PDOs hapticd does not use are left invalid, so nothing else shares
// the bus. TPDO2 carries the velocity when with_velocity.
std::vector<MappingEntry> pdo_mapping(std::uint8_t node, bool with_velocity);
inline constexpr std::uint32_t kCobIdInvalid = 0x80000000u;
// The bits of a COB-ID that verify compares (valid flag and 11-bit id; drives differ in the
// others, e.g. bit 30 "no RTR").
inline constexpr std::uint32_t kCobIdCompareMask = 0x800007FFu;
inline bool is_cob_id(canopen::SdoAddress at) noexcept {
  return at.subindex == 1 && (at.index & 0xFE00) == 0x1400
             ? true
             : at.subindex == 1 && (at.index & 0xFE00) == 0x1800;
}

}  // namespace hapticd::drivers::can::cia402
