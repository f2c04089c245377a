// The `report` profile's wire format: vendor-defined input and output reports (and optional
// feature reports) whose layout comes from the configuration, not from code (FFBeast's
// direct-control reports are one real example). The driver and its loopback peer both use
// these codecs. Pure: no OS headers; the RT functions never allocate.
//
// A report on the wire is what hidapi hands over: for a device with numbered reports the
// report id is byte 0 and the data follows; for an unnumbered device (all ids 0) input
// reports are the data alone, and output and feature reports still carry a leading 0.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

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

struct InputLayout {
  std::uint8_t report_id = 0;  // 0: the device does not number its reports
  std::size_t length = 0;      // data bytes after the id
  FieldSpec position;          // m or rad
  // The position is a counter of a multi-turn axis that wraps modulo 2^bits: the driver
  // unwraps it (position_count, one sample to the next) into the real motion.
  bool position_wraps = false;
  std::optional<FieldSpec> sequence;  // the device's sample counter (unsigned integer)
  std::optional<FieldSpec> status;    // status bits (integer)
  std::uint32_t fault_mask = 0;       // status bits that mean the device has faulted
  std::optional<FieldSpec> velocity;  // the device's own velocity estimate (m/s, rad/s)
};

// A field that switches something (the amplifier) with two raw values.
struct SwitchField {
  FieldSpec field;
  double on = 1.0;
  double off = 0.0;
};

struct OutputLayout {
  std::uint8_t report_id = 0;
  std::size_t length = 0;
  FieldSpec force;          // N or N m; scale is N per count
  double full_scale = 0.0;  // the largest |raw| force the device accepts
  std::optional<SwitchField> enable;
  std::optional<FieldSpec> keepalive;  // a counter bumped with every report (firmware watchdog)
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
// controller may command (device.max_force), which the force field must represent.
std::vector<std::string> validate(const ReportProfileLayout& layout, double max_force);

// What decoding one input report found.
enum class InputDecode : std::uint8_t {
  kOk,
  kOtherReport,  // a valid report with another id (not ours)
  kTooShort,     // shorter than the layout's data
  kEmpty,        // nothing at all (a numbered device must send its id)
};

struct InputValues {
  double position = 0.0;
  double velocity = 0.0;
  std::uint32_t sequence = 0;
  std::uint32_t status = 0;
  std::int64_t position_count = 0;  // an integer position field's raw count (decode only)
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

// RT-safe: called every tick. The force in `report` (prepared with its id and constant fields) set
// to `force`, clamped to +-full_scale counts.
void encode_force(double force, const OutputLayout& layout,
                  std::span<std::uint8_t> report) noexcept;
// RT-safe. The peer's side: the force and enable state an output report carries. False for a
// report of another id or too short.
struct OutputValues {
  double force = 0.0;
  bool enable = true;      // true when the layout has no enable field
  double keepalive = 0.0;  // raw
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
