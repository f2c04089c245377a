// The `pid` profile's wire format: the HID Physical Interface Device page (0x0F) as
// force-feedback wheels, sticks and open firmwares (OpenFFBoard and others) speak it. Report
// ids differ between devices, so every report and field is found by its usage in the parsed
// report descriptor (report_descriptor.h); a descriptor that lacks a report the profile needs
// is refused with that report named. The same code encodes what the driver sends and decodes
// what the loopback peer receives. Pure: no OS headers; the RT functions never allocate.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/hid/report_descriptor.h"

namespace hapticd::drivers::hid {

// Usages of the PID page (HID PID 1.0), those this profile uses.
namespace pid {
inline constexpr std::uint16_t kPage = 0x0F;
enum Usage : std::uint16_t {
  kSetEffectReport = 0x21,
  kEffectBlockIndex = 0x22,
  kEffectType = 0x25,
  kEtConstantForce = 0x26,
  kDuration = 0x50,
  kSamplePeriod = 0x51,
  kGain = 0x52,
  kTriggerButton = 0x53,
  kTriggerRepeatInterval = 0x54,
  kSetEnvelopeReport = 0x5A,
  kAttackLevel = 0x5B,
  kAttackTime = 0x5C,
  kFadeLevel = 0x5D,
  kFadeTime = 0x5E,
  kAxesEnable = 0x55,
  kDirectionEnable = 0x56,
  kDirection = 0x57,
  kMagnitude = 0x70,
  kSetConstantForceReport = 0x73,
  kEffectOperationReport = 0x77,
  kEffectOperation = 0x78,
  kOpEffectStart = 0x79,
  kOpEffectStartSolo = 0x7A,
  kOpEffectStop = 0x7B,
  kLoopCount = 0x7C,
  kDeviceGainReport = 0x7D,
  kDeviceGain = 0x7E,
  kPoolReport = 0x7F,
  kRamPoolSize = 0x80,
  kSimultaneousEffectsMax = 0x83,
  kBlockLoadReport = 0x89,
  kBlockLoadStatus = 0x8B,
  kBlockLoadSuccess = 0x8C,
  kBlockLoadFull = 0x8D,
  kBlockLoadError = 0x8E,
  kBlockFreeReport = 0x90,
  kStateReport = 0x92,
  kEffectPlaying = 0x94,
  kDeviceControlReport = 0x95,
  kDeviceControl = 0x96,
  kDcEnableActuators = 0x97,
  kDcDisableActuators = 0x98,
  kDcStopAllEffects = 0x99,
  kDcDeviceReset = 0x9A,
  kDevicePaused = 0x9F,
  kActuatorsEnabled = 0xA0,
  kSafetySwitch = 0xA4,
  kActuatorOverrideSwitch = 0xA5,
  kActuatorPower = 0xA6,
  kStartDelay = 0xA7,
  kDeviceManagedPool = 0xA9,
  kSharedParameterBlocks = 0xAA,
  kCreateNewEffectReport = 0xAB,
  kRamPoolAvailable = 0xAC,
};
constexpr std::uint32_t u(Usage id) noexcept { return usage(kPage, id); }
}  // namespace pid

// Generic Desktop X and Y: the usual position axes, and the Axes Enable bits of Set Effect.
inline constexpr std::uint32_t kGenericDesktopX = usage(0x01, 0x30);
inline constexpr std::uint32_t kGenericDesktopY = usage(0x01, 0x31);

// One report the profile uses.
struct ReportRef {
  bool present = false;
  ReportKind kind = ReportKind::kOutput;
  std::uint8_t id = 0;
  std::size_t data_bytes = 0;
  // The report as hidapi takes it for output and feature reports: id (0 when unnumbered) first.
  std::size_t wire_size() const noexcept { return data_bytes + 1; }
};

// One value in a report's data: where it is and how it reads.
struct Slot {
  bool present = false;
  std::uint32_t bit_offset = 0;
  std::uint32_t bit_size = 0;
  std::int64_t logical_min = 0;
  std::int64_t logical_max = 0;
  bool is_signed = false;
};

// A usage selected in a report: an array slot holding `value`, or a one-bit variable set to 1.
struct Choice {
  Slot slot;
  std::int64_t value = 0;
};

struct PidLayout {
  bool numbered = false;
  // The position axes (joint i's is entry i) and the optional sample counter, in one input
  // report.
  ReportRef position_report;
  std::vector<Slot> positions;
  Slot sequence;
  // Set Effect (output). Axes Enable X and Y, and the Direction's first two instances (its
  // ordinals 1 and 2, X's and Y's).
  ReportRef set_effect;
  Slot se_block, se_duration, se_trigger_repeat, se_sample_period, se_start_delay, se_gain,
      se_trigger_button, se_axis_x, se_axis_y, se_direction_enable, se_direction, se_direction_y;
  Choice se_constant;
  // Set Constant Force (output).
  ReportRef set_constant;
  Slot sc_block, sc_magnitude;
  // Effect Operation (output).
  ReportRef effect_operation;
  Slot eo_block, eo_loop_count;
  Choice eo_start, eo_stop;
  // PID Device Control (output).
  ReportRef device_control;
  Choice dc_enable, dc_disable, dc_stop_all, dc_reset;
  // Create New Effect (feature) and PID Block Load (feature, read back).
  ReportRef create_effect;
  Choice ce_constant;
  ReportRef block_load;
  Slot bl_block, bl_ram_pool;
  Choice bl_success, bl_full, bl_error;
  // Optional: Device Gain (output), Block Free (output), PID State (input).
  ReportRef device_gain;
  Slot dg_gain;
  ReportRef block_free;
  Slot bf_block;
  ReportRef state;
  Slot st_paused, st_actuators_enabled, st_safety_switch, st_override, st_power, st_playing;
};

struct PidFind {
  std::optional<PidLayout> layout;
  std::string error;  // names the missing report or field
};

// The PID State report as PositionSample::status bits: each set bit is a condition that keeps
// the device from rendering force (a bit whose field the device lacks is never set).
enum PidStatus : std::uint32_t {
  kPidPaused = 1u << 0,             // Device Paused reads 1
  kPidActuatorsDisabled = 1u << 1,  // Actuators Enabled reads 0
  kPidSafetySwitchOff = 1u << 2,    // Safety Switch reads 0
  kPidOverride = 1u << 3,           // Actuator Override Switch reads 1
  kPidPowerOff = 1u << 4,           // Actuator Power reads 0
  kPidEffectStopped = 1u << 5,      // Effect Playing reads 0
};
// What faults the loop by default: the device turned its actuators off. That bit answers the
// host's own Device Control, so every firmware that declares it drives it. Safety Switch,
// Actuator Override and Actuator Power mean what a board makes them mean, and common firmware
// declares bits it never sets (OpenFFBoard's Safety Switch reads 0 always): a configuration
// adds them for a board that drives them (docs/drivers/hid.md).
inline constexpr std::uint32_t kPidDefaultFaultMask = kPidActuatorsDisabled;

// Not RT-safe. Finds every report and field the profile needs. `position_usages` are the input
// usages read as the joints' positions (e.g. kGenericDesktopX), all in one report;
// `sequence_usage` an optional input usage in that report read as the device's sample counter
// (0: none). Two joints need Set Effect's Axes Enable X and Y and two Direction instances (one
// effect per axis, docs/drivers/hid.md "Two axes").
PidFind find_pid_layout(const ParsedDescriptor& d, std::span<const std::uint32_t> position_usages,
                        std::uint32_t sequence_usage = 0);
// One joint's.
PidFind find_pid_layout(const ParsedDescriptor& d, std::uint32_t position_usage,
                        std::uint32_t sequence_usage = 0);

// Not RT-safe. A zeroed report for `ref`, id first (for an unnumbered device's input report:
// no id byte, as hid_read returns it).
std::vector<std::uint8_t> make_report(const ReportRef& ref, bool numbered);

// RT-safe: called every tick. The data part of a report as it travels (after the id byte when there
// is one).
std::span<std::uint8_t> data_of(std::span<std::uint8_t> report, const ReportRef& ref,
                                bool numbered) noexcept;
std::span<const std::uint8_t> data_of(std::span<const std::uint8_t> report, const ReportRef& ref,
                                      bool numbered) noexcept;
// RT-safe: called every tick. Whether `report` (as it travels) is `ref`: its id matches and it is
// long enough.
bool is_report(std::span<const std::uint8_t> report, const ReportRef& ref, bool numbered) noexcept;

// RT-safe: called every tick, on the data part. A missing slot is neither written nor read (reads
// 0).
void set_slot(std::span<std::uint8_t> data, const Slot& s, std::int64_t value) noexcept;
std::int64_t get_slot(std::span<const std::uint8_t> data, const Slot& s) noexcept;
void choose(std::span<std::uint8_t> data, const Choice& c) noexcept;
bool chosen(std::span<const std::uint8_t> data, const Choice& c) noexcept;
// RT-safe: called every tick. The PidStatus bits of a PID State report's data.
std::uint32_t pid_status(std::span<const std::uint8_t> data, const PidLayout& l) noexcept;

// An axis' own Direction (Direction Enable clear, two axes): `degrees` in [0, 360] onto the
// slot's whole logical range, 0 its minimum and 360 its maximum.
std::int64_t direction_value(const Slot& dir, double degrees) noexcept;

// The slot's HID null value (outside its logical range, all ones where possible): PID reads
// a null Duration as infinite and a null Trigger Button as none.
std::int64_t null_value(const Slot& s) noexcept;

}  // namespace hapticd::drivers::hid
