// The `report` profile's wire format: vendor-defined input and output reports (and optional
// feature reports) whose layout comes from the configuration, not from code (FFBeast's
// direct-control reports are one real example). The driver and its loopback peer both use
// these codecs. Pure: no OS headers; the RT functions never allocate.
//
// A report on the wire is what hidapi hands over: for a device with numbered reports the
// report id is byte 0 and the data follows; for an unnumbered device (all ids 0) input
// reports are the data alone, and output and feature reports still carry a leading 0.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "base/joints.h"
#include "drivers/field/field.h"

namespace hapticd::drivers::hid {

// A report's fields are the shared field codec's (drivers/field/field.h).
using field::counter_modulus;
using field::Endian;
using field::FieldSpec;
using field::FieldType;
using field::is_integer;
using field::kMaxFieldBits;
using field::raw_max;
using field::raw_min;
using field::read_count;
using field::read_raw;
using field::read_si;
using field::si_to_raw;
using field::type_name;
using field::typed;
using field::write_raw;
using field::write_si;
using field::write_wrapped;

// Longest data part of a report the profile accepts (the HID limit for a high-speed
// interrupt endpoint); anything longer is a configuration error, not a buffer overrun.
inline constexpr std::size_t kMaxReportData = 1024;

// One joint's position field beyond the first (the list form `positions: [...]`).
struct PositionField {
  FieldSpec field;
  bool wraps = false;
};

struct InputLayout {
  std::uint8_t report_id = 0;  // 0: the device does not number its reports
  std::size_t length = 0;      // data bytes after the id
  FieldSpec position;          // joint 0's: m or rad
  // The position is a counter of a multi-turn axis that wraps modulo 2^bits: the driver
  // unwraps it (position_count, one sample to the next) into the real motion.
  bool position_wraps = false;
  // Joints 1.. of a mechanism of several (device.kinematics). The one-joint key `position`
  // is joint 0 above whichever form the configuration used, so every one-joint layout reads
  // as it did; `listed` says the list form was given (it names the keys in messages).
  std::vector<PositionField> more_positions;
  bool listed = false;
  std::optional<FieldSpec> sequence;  // the device's sample counter (unsigned integer)
  std::optional<FieldSpec> status;    // status bits (integer)
  std::uint32_t fault_mask = 0;       // status bits that mean the device has faulted
  std::optional<FieldSpec> velocity;  // the device's own velocity estimate (m/s, rad/s)

  std::size_t joints() const noexcept { return 1 + more_positions.size(); }
  // Joint j's field, j < joints().
  PositionField joint(std::size_t j) const noexcept {
    return j == 0 ? PositionField{position, position_wraps} : more_positions[j - 1];
  }
  // The key naming joint j's field: "input.position" or "input.positions[j]".
  std::string key(std::size_t j) const;
};

// A field that switches something (the amplifier) with two raw values.
struct SwitchField {
  FieldSpec field;
  double on = 1.0;
  double off = 0.0;
};

// One joint's force field beyond the first (the list form `forces: [...]`).
struct ForceField {
  FieldSpec field;
  double full_scale = 0.0;
};

struct OutputLayout {
  std::uint8_t report_id = 0;
  std::size_t length = 0;
  FieldSpec force;                      // joint 0's: N or N m; scale is N per count
  double full_scale = 0.0;              // the largest |raw| force the device accepts
  std::vector<ForceField> more_forces;  // joints 1.., as InputLayout::more_positions
  bool listed = false;
  std::optional<SwitchField> enable;
  std::optional<FieldSpec> keepalive;  // a counter bumped with every report (firmware watchdog)

  std::size_t joints() const noexcept { return 1 + more_forces.size(); }
  ForceField joint(std::size_t j) const noexcept {
    return j == 0 ? ForceField{force, full_scale} : more_forces[j - 1];
  }
  std::string key(std::size_t j) const;  // "output.force" or "output.forces[j]"
};

// A feature report that carries one value (enable on/off, gain, watchdog timeout).
struct FeatureLayout {
  std::uint8_t report_id = 0;
  std::size_t length = 0;
  FieldSpec field;
  double on = 1.0;   // the value written (enable: on)
  double off = 0.0;  // enable only: the value that switches it off
};

struct ReportProfileLayout {
  InputLayout input;
  OutputLayout output;
  std::optional<FeatureLayout> enable_feature;
  std::optional<FeatureLayout> gain_feature;
  std::optional<FeatureLayout> watchdog_feature;

  bool numbered() const noexcept { return input.report_id != 0; }
};

// Not RT-safe. Everything wrong with the layout, each message "<where>: <what>" with <where> a
// key path below the profile ("input.sequence", "output"). `max_force`: the force the
// controller may command (device.max_force), which the force field must represent: joint i's
// is entry i (the last entry stands for joints past the span's end).
std::vector<std::string> validate(const ReportProfileLayout& layout,
                                  std::span<const double> max_force);
std::vector<std::string> validate(const ReportProfileLayout& layout, double max_force);

// What decoding one input report found.
enum class InputDecode : std::uint8_t {
  kOk,
  kOtherReport,  // a valid report with another id (not ours)
  kTooShort,     // shorter than the layout's data
  kEmpty,        // nothing at all (a numbered device must send its id)
};

struct InputValues {
  std::array<double, base::kMaxJoints> position{};  // joint i's is entry i
  double velocity = 0.0;
  std::uint32_t sequence = 0;
  std::uint32_t status = 0;
  // An integer position field's raw count (decode only), joint i's entry i.
  std::array<std::int64_t, base::kMaxJoints> position_count{};
};

// RT-safe: called every tick. Decodes one report as hid_read returned it.
InputDecode decode_input(std::span<const std::uint8_t> report, const InputLayout& layout,
                         InputValues& out) noexcept;
// RT-safe. Writes an input report (id first when numbered) into `report`, which must hold
// input_report_size(layout) bytes. The peer's side.
void encode_input(const InputValues& in, const InputLayout& layout,
                  std::span<std::uint8_t> report) noexcept;
std::size_t input_report_size(const InputLayout& layout) noexcept;

// Size of an output or feature report as hid_write / hid_send_feature_report take it: the
// report id (0 when unnumbered) and the data.
inline std::size_t wire_size(std::size_t data_length) noexcept { return data_length + 1; }

// RT-safe: called every tick. The forces in `report` (prepared with its id and constant fields)
// set to `forces`, joint i's to entry i, each clamped to its field's +-full_scale counts.
// `forces` holds layout.joints() values.
void encode_force(std::span<const double> forces, const OutputLayout& layout,
                  std::span<std::uint8_t> report) noexcept;
// RT-safe. The peer's side: the force and enable state an output report carries. False for a
// report of another id or too short.
struct OutputValues {
  std::array<double, base::kMaxJoints> force{};  // joint i's is entry i
  bool enable = true;                            // true when the layout has no enable field
  double keepalive = 0.0;                        // raw
};
bool decode_output(std::span<const std::uint8_t> report, const OutputLayout& layout,
                   OutputValues& out) noexcept;

// RT-safe. `value` (raw) written into a feature report buffer of wire_size(length) bytes.
void encode_feature(double raw, const FeatureLayout& layout,
                    std::span<std::uint8_t> report) noexcept;
// The raw value of a feature report; nothing for another id or a short report.
std::optional<double> decode_feature(std::span<const std::uint8_t> report,
                                     const FeatureLayout& layout) noexcept;

}  // namespace hapticd::drivers::hid
