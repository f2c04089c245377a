// CiA 402 (drives and motion control) as hapticd uses it, pure: the objects, the power state
// machine seen from both ends (the statusword a drive reports, the controlword that moves it
// on, and - for the simulated drive - how a controlword moves a state), and the PDO mapping
// of cyclic synchronous torque that the driver configures or verifies (docs/drivers/can.md).
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
inline constexpr canopen::SdoAddress kMaxTorque{0x6072, 0};                 // per mille of 0x6076
inline constexpr canopen::SdoAddress kRatedTorque{0x6076, 0};               // mN m
inline constexpr canopen::SdoAddress kInterpolationPeriodValue{0x60C2, 1};  // u8
inline constexpr canopen::SdoAddress kInterpolationPeriodIndex{0x60C2, 2};  // i8, power of ten (s)
inline constexpr canopen::SdoAddress kPositionActual{0x6064, 0};
inline constexpr canopen::SdoAddress kVelocityActual{0x606C, 0};

inline constexpr std::uint16_t kDeviceProfile402 = 402;  // low 16 bits of 0x1000
inline constexpr std::int8_t kModeCyclicSynchronousTorque = 10;

// Statusword bit 4, voltage enabled: the power stage has its DC-link voltage. At 0 in switch
// on disabled the drive may still be charging its DC link after mains on (it refuses the
// shutdown command until then: KEB COMBIVERT F6, SMC LECSN-T), or have no mains at all.
inline constexpr std::uint16_t kSwVoltageEnabled = 1u << 4;
// Statusword bit 11, internal limit active: the drive limits a value itself (0x6072 max
// torque, a current limit, a thermal derating): a force the wall did not command.
inline constexpr std::uint16_t kSwInternalLimitActive = 1u << 11;

// 0x60C2 interpolation time period: value x 10^index s. The exact period T where it fits in
// the two numbers (exact false otherwise: the nearest that does).
struct InterpolationPeriod {
  std::uint8_t value = 1;
  std::int8_t index = -3;
  bool exact = true;
};
InterpolationPeriod interpolation_period(double period_s) noexcept;

// Controlword commands (the bits that matter; docs/drivers/can.md).
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
  bool cob_id = false;  // a PDO's COB-ID: value holds the CAN id and the valid bit only; the
                        // drive's own bits are read first and kept (cob_id_to_write)
};
// In write order (CiA 301 §7.5.2.36): each PDO is invalidated, its transmission type set (1:
// every SYNC), its mapping count set to 0, the entries written, the count written, and the PDO
// made valid again. The PDOs hapticd does not use are left invalid, so nothing else shares
// the bus. TPDO2 carries the velocity when with_velocity.
std::vector<MappingEntry> pdo_mapping(std::uint8_t node, bool with_velocity);
inline constexpr std::uint32_t kCobIdInvalid = 0x80000000u;
// Bit 30: for a TPDO "no RTR allowed", for an RPDO reserved. Many drives require it as they
// ship it (CANopenNode's TPDO default is 0xC0000180 + node) and abort a write that clears it
// with 0x06090030; so it is read and kept.
inline constexpr std::uint32_t kCobIdNoRtr = 0x40000000u;
// The COB-ID to write over what the drive holds (`current`): its bit 30 kept, the valid bit
// (31) and the 11-bit CAN id from `wanted`, bits 11-29 zero (CiA 301: 11-bit ids). When the
// id already matches, only bit 31 changes.
inline constexpr std::uint32_t cob_id_to_write(std::uint32_t current,
                                               std::uint32_t wanted) noexcept {
  return (current & kCobIdNoRtr) | (wanted & (kCobIdInvalid | 0x7FFu));
}
// The bits of a COB-ID that verify compares (valid flag and 11-bit id; drives differ in the
// others, e.g. bit 30 "no RTR").
inline constexpr std::uint32_t kCobIdCompareMask = 0x800007FFu;
inline bool is_cob_id(canopen::SdoAddress at) noexcept {
  return at.subindex == 1 && (at.index & 0xFE00) == 0x1400
             ? true
             : at.subindex == 1 && (at.index & 0xFE00) == 0x1800;
}

}  // namespace hapticd::drivers::can::cia402
