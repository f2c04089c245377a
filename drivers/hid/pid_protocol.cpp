#include "drivers/hid/pid_protocol.h"

#include <algorithm>
#include <cmath>

#include "base/hex.h"

namespace hapticd::drivers::hid {
namespace {

std::string usage_text(std::uint32_t u) {
  return base::hex(usage_page_of(u), 2) + ":" + base::hex(u & 0xFFFFu, 2);
}

Slot slot_of(const ReportField& f, std::uint32_t element) {
  Slot s;
  s.present = f.bit_size <= 32;  // wider values are not read by this profile
  s.bit_offset = f.bit_offset + element * f.bit_size;
  s.bit_size = f.bit_size;
  s.logical_min = f.logical_min;
  s.logical_max = f.logical_max;
  s.is_signed = f.is_signed();
  return s;
}

class Finder {
 public:
  explicit Finder(const ParsedDescriptor& d) : d_(d) {}

  // The report whose fields sit in the logical collection `collection`, or (where the report
  // has one) in `alternative`: hid-pidff (drivers/hid/usbhid/hid-pidff.c, pidff_reports and
  // pidff_find_reports) takes a report by the logical collection around its first field, so it
  // finds Device Control by 0x96, the collection of its array ("device_control is really 0x95,
  // but 0x96 specified as it is the usage of the only field in that report"), and drives the
  // SideWinder-lineage firmwares that declare 0x96 alone.
  ReportRef report(pid::Usage collection, ReportKind expected, const char* name, bool required,
                   std::uint32_t alternative = 0) {
    for (const std::uint32_t c : {pid::u(collection), alternative}) {
      if (c == 0) continue;
      for (const ReportField& f : d_.fields) {
        if (f.inside(c)) return found(f, c, expected, name, required);
      }
    }
    if (required) {
      fail(std::string("the report descriptor has no PID ") + name + " report (" +
           usage_text(pid::u(collection)) +
           (alternative != 0 ? ", nor a " + usage_text(alternative) + " collection" : "") + ")");
    }
    return {};
  }

  // The variable element with usage `u` in `ref` (inside `collection` when non-zero).
  Slot slot(const ReportRef& ref, std::uint32_t u, std::uint32_t collection = 0) const {
    if (!ref.present) return {};
    for (const ReportField& f : fields_of(ref)) {
      if (!f.is_variable() || (collection != 0 && !f.inside(collection))) continue;
      for (std::uint32_t i = 0; i < f.count; ++i) {
        if (f.usage_of(i) == u) return slot_of(f, i);
      }
    }
    return {};
  }

  // Element `n` of the variable elements inside `collection`, counted across its fields in
  // order (the Direction's instances: one field of count 2, or two fields).
  Slot nth_in(const ReportRef& ref, std::uint32_t collection, std::uint32_t n) const {
    if (!ref.present) return {};
    for (const ReportField& f : fields_of(ref)) {
      if (!f.is_variable() || !f.inside(collection)) continue;
      if (n < f.count) return slot_of(f, n);
      n -= f.count;
    }
    return {};
  }

  // Selecting usage `u` in `ref`: an array that lists it, or a one-bit variable.
  Choice choice(const ReportRef& ref, std::uint32_t u) const {
    if (!ref.present) return {};
    for (const ReportField& f : fields_of(ref)) {
      if (f.is_variable()) continue;
      const auto it = std::find(f.usages.begin(), f.usages.end(), u);
      if (it != f.usages.end()) {
        return {slot_of(f, 0), f.logical_min + (it - f.usages.begin())};
      }
    }
    const Slot s = slot(ref, u);
    return {s, 1};
  }

  void need(const Slot& s, const char* report, const char* field, std::uint32_t u) {
    if (!s.present) {
      fail(std::string("the PID ") + report + " report has no " + field + " (" + usage_text(u) +
           ")");
    }
  }
  void need(const Choice& c, const char* report, const char* field, std::uint32_t u) {
    need(c.slot, report, field, u);
  }

  const std::string& error() const { return error_; }

 private:
  std::vector<ReportField> fields_of(const ReportRef& ref) const {
    std::vector<ReportField> out;
    for (const ReportField& f : d_.fields) {
      if (f.kind == ref.kind && f.report_id == ref.id && !f.is_constant()) out.push_back(f);
    }
    return out;
  }
  void fail(const std::string& what) {
    if (error_.empty()) error_ = what;
  }
  ReportRef found(const ReportField& f, std::uint32_t c, ReportKind expected, const char* name,
                  bool required) {
    if (f.kind != expected) {
      if (required) {
        fail(std::string("the PID ") + name + " report (" + usage_text(c) + ") is an " +
             to_string(f.kind) + " report in this descriptor; the profile needs it as " +
             to_string(expected) + " report");
      }
      return {};
    }
    const ReportInfo* info = d_.find_report(f.kind, f.report_id);
    return {true, f.kind, f.report_id, info != nullptr ? info->data_bytes() : 0};
  }

  const ParsedDescriptor& d_;
  std::string error_;
};

void find_effect_reports(Finder& f, PidLayout& l) {
  using namespace pid;
  l.set_effect = f.report(kSetEffectReport, ReportKind::kOutput, "Set Effect", true);
  l.se_block = f.slot(l.set_effect, u(kEffectBlockIndex));
  l.se_constant = f.choice(l.set_effect, u(kEtConstantForce));
  f.need(l.se_constant, "Set Effect", "constant force effect type", u(kEtConstantForce));
  l.se_duration = f.slot(l.set_effect, u(kDuration));
  l.se_trigger_repeat = f.slot(l.set_effect, u(kTriggerRepeatInterval));
  l.se_sample_period = f.slot(l.set_effect, u(kSamplePeriod));
  l.se_start_delay = f.slot(l.set_effect, u(kStartDelay));
  l.se_gain = f.slot(l.set_effect, u(kGain));
  l.se_trigger_button = f.slot(l.set_effect, u(kTriggerButton));
  l.se_axis_x = f.slot(l.set_effect, kGenericDesktopX, u(kAxesEnable));
  l.se_axis_y = f.slot(l.set_effect, kGenericDesktopY, u(kAxesEnable));
  l.se_direction_enable = f.slot(l.set_effect, u(kDirectionEnable));
  l.se_direction = f.nth_in(l.set_effect, u(kDirection), 0);
  l.se_direction_y = f.nth_in(l.set_effect, u(kDirection), 1);

  l.set_constant =
      f.report(kSetConstantForceReport, ReportKind::kOutput, "Set Constant Force", true);
  l.sc_block = f.slot(l.set_constant, u(kEffectBlockIndex));
  l.sc_magnitude = f.slot(l.set_constant, u(kMagnitude));
  f.need(l.sc_magnitude, "Set Constant Force", "Magnitude", u(kMagnitude));

  l.effect_operation =
      f.report(kEffectOperationReport, ReportKind::kOutput, "Effect Operation", true);
  l.eo_block = f.slot(l.effect_operation, u(kEffectBlockIndex));
  l.eo_loop_count = f.slot(l.effect_operation, u(kLoopCount));
  l.eo_start = f.choice(l.effect_operation, u(kOpEffectStart));
  l.eo_stop = f.choice(l.effect_operation, u(kOpEffectStop));
  f.need(l.eo_start, "Effect Operation", "Op Effect Start", u(kOpEffectStart));
}

void find_device_reports(Finder& f, PidLayout& l) {
  using namespace pid;
  l.device_control = f.report(kDeviceControlReport, ReportKind::kOutput, "Device Control", true,
                              u(kDeviceControl));
  l.dc_enable = f.choice(l.device_control, u(kDcEnableActuators));
  l.dc_disable = f.choice(l.device_control, u(kDcDisableActuators));
  l.dc_stop_all = f.choice(l.device_control, u(kDcStopAllEffects));
  l.dc_reset = f.choice(l.device_control, u(kDcDeviceReset));
  f.need(l.dc_enable, "Device Control", "DC Enable Actuators", u(kDcEnableActuators));
  f.need(l.dc_disable, "Device Control", "DC Disable Actuators", u(kDcDisableActuators));
  f.need(l.dc_stop_all, "Device Control", "DC Stop All Effects", u(kDcStopAllEffects));

  l.create_effect =
      f.report(kCreateNewEffectReport, ReportKind::kFeature, "Create New Effect", true);
  l.ce_constant = f.choice(l.create_effect, u(kEtConstantForce));
  f.need(l.ce_constant, "Create New Effect", "constant force effect type", u(kEtConstantForce));

  l.block_load = f.report(kBlockLoadReport, ReportKind::kFeature, "Block Load", true);
  l.bl_block = f.slot(l.block_load, u(kEffectBlockIndex));
  l.bl_ram_pool = f.slot(l.block_load, u(kRamPoolAvailable));
  l.bl_success = f.choice(l.block_load, u(kBlockLoadSuccess));
  l.bl_full = f.choice(l.block_load, u(kBlockLoadFull));
  l.bl_error = f.choice(l.block_load, u(kBlockLoadError));
  f.need(l.bl_block, "Block Load", "Effect Block Index", u(kEffectBlockIndex));
  f.need(l.bl_success, "Block Load", "Block Load Success status", u(kBlockLoadSuccess));

  l.device_gain = f.report(kDeviceGainReport, ReportKind::kOutput, "Device Gain", false);
  l.dg_gain = f.slot(l.device_gain, u(kDeviceGain));
  l.block_free = f.report(kBlockFreeReport, ReportKind::kOutput, "Block Free", false);
  l.bf_block = f.slot(l.block_free, u(kEffectBlockIndex));
  l.state = f.report(kStateReport, ReportKind::kInput, "PID State", false);
  l.st_paused = f.slot(l.state, u(kDevicePaused));
  l.st_actuators_enabled = f.slot(l.state, u(kActuatorsEnabled));
  l.st_safety_switch = f.slot(l.state, u(kSafetySwitch));
  l.st_override = f.slot(l.state, u(kActuatorOverrideSwitch));
  l.st_power = f.slot(l.state, u(kActuatorPower));
  l.st_playing = f.slot(l.state, u(kEffectPlaying));
}

// The input report holding the position usages (every one in the same report), and the
// sequence usage beside them.
std::string find_positions(const ParsedDescriptor& d, std::span<const std::uint32_t> usages,
                           std::uint32_t sequence_usage, PidLayout& l) {
  for (std::size_t j = 0; j < usages.size(); ++j) {
    Slot found;
    for (const ReportField& f : d.fields) {
      if (f.kind != ReportKind::kInput || !f.is_variable() || f.is_constant()) continue;
      if (l.position_report.present && f.report_id != l.position_report.id) continue;
      for (std::uint32_t i = 0; i < f.count && !found.present; ++i) {
        if (f.usage_of(i) != usages[j]) continue;
        const ReportInfo* info = d.find_report(f.kind, f.report_id);
        l.position_report = {true, f.kind, f.report_id, info != nullptr ? info->data_bytes() : 0};
        found = slot_of(f, i);
      }
    }
    const std::string key = usages.size() == 1
                                ? "device.hid.pid.position"
                                : "device.hid.pid.positions[" + std::to_string(j) + "]";
    if (!found.present) {
      return "the report descriptor has no input field with the position usage " +
             usage_text(usages[j]) +
             (j > 0 ? " in input report " + std::to_string(l.position_report.id) +
                          ", which holds joint 0's"
                    : std::string()) +
             " (" + key + ")";
    }
    l.positions.push_back(found);
  }
  if (sequence_usage != 0) {
    for (const ReportField& f : d.fields) {
      if (f.kind != ReportKind::kInput || f.report_id != l.position_report.id || !f.is_variable()) {
        continue;
      }
      for (std::uint32_t i = 0; i < f.count && !l.sequence.present; ++i) {
        if (f.usage_of(i) == sequence_usage) l.sequence = slot_of(f, i);
      }
    }
    if (!l.sequence.present) {
      return "the position's input report has no field with the sequence usage " +
             usage_text(sequence_usage) + " (device.hid.pid.sequence)";
    }
  }
  return "";
}

// One effect per axis: each selects its own axis and carries its own Direction.
std::string check_axes(const PidLayout& l) {
  if (l.positions.size() < 2) return "";
  if (l.positions.size() > 2) {
    return "the pid profile drives one or two joints (X and Y), not " +
           std::to_string(l.positions.size());
  }
  const auto missing = [](const char* what, std::uint32_t u) {
    return std::string("the PID Set Effect report has no ") + what + " (" + usage_text(u) +
           "), which a force on each of two axes needs (docs/drivers/hid.md, \"Two axes\")";
  };
  if (!l.se_axis_x.present) return missing("Axes Enable X", kGenericDesktopX);
  if (!l.se_axis_y.present) return missing("Axes Enable Y", kGenericDesktopY);
  if (!l.se_direction_y.present)
    return missing("second Direction instance", pid::u(pid::kDirection));
  return "";
}

}  // namespace

PidFind find_pid_layout(const ParsedDescriptor& d, std::span<const std::uint32_t> position_usages,
                        std::uint32_t sequence_usage) {
  PidLayout l;
  l.numbered = d.numbered;
  Finder f(d);
  find_effect_reports(f, l);
  find_device_reports(f, l);
  if (!f.error().empty()) return {std::nullopt, f.error()};
  if (std::string e = find_positions(d, position_usages, sequence_usage, l); !e.empty()) {
    return {std::nullopt, e};
  }
  if (std::string e = check_axes(l); !e.empty()) return {std::nullopt, e};
  return {l, ""};
}

PidFind find_pid_layout(const ParsedDescriptor& d, std::uint32_t position_usage,
                        std::uint32_t sequence_usage) {
  return find_pid_layout(d, std::span<const std::uint32_t>(&position_usage, 1), sequence_usage);
}

std::vector<std::uint8_t> make_report(const ReportRef& ref, bool numbered) {
  const bool id_byte = numbered || ref.kind != ReportKind::kInput;
  std::vector<std::uint8_t> r(ref.data_bytes + (id_byte ? 1 : 0), 0);
  if (id_byte) r[0] = ref.id;
  return r;
}

std::span<std::uint8_t> data_of(std::span<std::uint8_t> report, const ReportRef& ref,
                                bool numbered) noexcept {
  const bool id_byte = numbered || ref.kind != ReportKind::kInput;
  return id_byte && !report.empty() ? report.subspan(1) : report;
}

std::span<const std::uint8_t> data_of(std::span<const std::uint8_t> report, const ReportRef& ref,
                                      bool numbered) noexcept {
  const bool id_byte = numbered || ref.kind != ReportKind::kInput;
  return id_byte && !report.empty() ? report.subspan(1) : report;
}

bool is_report(std::span<const std::uint8_t> report, const ReportRef& ref, bool numbered) noexcept {
  if (!ref.present) return false;
  const bool id_byte = numbered || ref.kind != ReportKind::kInput;
  if (id_byte && (report.empty() || report[0] != ref.id)) return false;
  return report.size() >= ref.data_bytes + (id_byte ? 1 : 0);
}

void set_slot(std::span<std::uint8_t> data, const Slot& s, std::int64_t value) noexcept {
  if (!s.present) return;
  put_bits(data, s.bit_offset, s.bit_size, static_cast<std::uint32_t>(value));
}

std::int64_t get_slot(std::span<const std::uint8_t> data, const Slot& s) noexcept {
  if (!s.present) return 0;
  return field_value(get_bits(data, s.bit_offset, s.bit_size), s.bit_size, s.is_signed);
}

void choose(std::span<std::uint8_t> data, const Choice& c) noexcept {
  set_slot(data, c.slot, c.value);
}

bool chosen(std::span<const std::uint8_t> data, const Choice& c) noexcept {
  return c.slot.present && get_slot(data, c.slot) == c.value;
}

std::uint32_t pid_status(std::span<const std::uint8_t> data, const PidLayout& l) noexcept {
  std::uint32_t bits = 0;
  const auto flag = [&](const Slot& s, bool set_when_one, std::uint32_t bit) {
    if (s.present && (get_slot(data, s) != 0) == set_when_one) bits |= bit;
  };
  flag(l.st_paused, true, kPidPaused);
  flag(l.st_actuators_enabled, false, kPidActuatorsDisabled);
  flag(l.st_safety_switch, false, kPidSafetySwitchOff);
  flag(l.st_override, true, kPidOverride);
  flag(l.st_power, false, kPidPowerOff);
  flag(l.st_playing, false, kPidEffectStopped);
  return bits;
}

std::int64_t direction_value(const Slot& dir, double degrees) noexcept {
  const double span = static_cast<double>(dir.logical_max - dir.logical_min);
  return dir.logical_min + std::llround(degrees / 360.0 * span);
}

std::int64_t null_value(const Slot& s) noexcept {
  if (s.bit_size == 0 || s.bit_size > 32) return 0;
  const std::int64_t all_ones =
      s.bit_size == 32 ? 0xFFFFFFFFll : (std::int64_t{1} << s.bit_size) - 1;
  const auto outside = [&](std::int64_t bits) {
    const std::int64_t v = field_value(static_cast<std::uint32_t>(bits), s.bit_size, s.is_signed);
    return v < s.logical_min || v > s.logical_max;
  };
  if (outside(all_ones)) return all_ones;
  // All ones reads inside (-1 of a signed range): an end of the field's width may not.
  const std::int64_t lowest = s.is_signed ? std::int64_t{1} << (s.bit_size - 1) : 0;
  if (outside(lowest)) return lowest;
  if (s.is_signed && outside(lowest - 1)) return lowest - 1;
  return all_ones;  // every value of the width is in range: there is no null
}

}  // namespace hapticd::drivers::hid
