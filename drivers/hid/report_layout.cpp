#include "drivers/hid/report_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hapticd::drivers::hid {
namespace {

struct Named {
  std::string where;
  const FieldSpec* field;
};

// "bytes 5..6", or for a field that shares a byte with others: "byte 5, byte 6 bits 0..3".
std::string bytes_text(const FieldSpec& f) {
  bool whole = true;
  for (std::size_t k = f.byte; k < f.end(); ++k) whole = whole && f.mask_of_byte(k) == 0xFF;
  if (whole) return "bytes " + std::to_string(f.byte) + ".." + std::to_string(f.end() - 1);
  std::string s;
  for (std::size_t k = f.byte; k < f.end(); ++k) {
    const unsigned m = f.mask_of_byte(k);
    s += (s.empty() ? "byte " : ", byte ") + std::to_string(k);
    if (m == 0xFF) continue;
    const int lo = __builtin_ctz(m), hi = 31 - __builtin_clz(m);
    s += lo == hi ? " bit " + std::to_string(lo)
                  : " bits " + std::to_string(lo) + ".." + std::to_string(hi);
  }
  return s;
}

bool overlap(const FieldSpec& f, const FieldSpec& g) {
  for (std::size_t k = std::max(f.byte, g.byte); k < std::min(f.end(), g.end()); ++k) {
    if ((f.mask_of_byte(k) & g.mask_of_byte(k)) != 0) return true;
  }
  return false;
}

// The field's shape: a width and a start an integer of at most 32 bits can have, an f32 whole.
void check_shape(const std::string& where, const FieldSpec& f, std::vector<std::string>& errors) {
  if (f.bits < 1 || f.bits > kMaxFieldBits) {
    errors.push_back(where + ".bits: must be 1.." + std::to_string(kMaxFieldBits) + ", got " +
                     std::to_string(f.bits));
  } else if (f.bit > 7) {
    errors.push_back(where + ".bit: must be 0..7 (a later byte is a larger `byte`), got " +
                     std::to_string(f.bit));
  } else if (f.is_float && (f.bits != 32 || f.bit != 0)) {
    errors.push_back(where + ": an f32 is 32 bits from bit 0");
  }
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Length, fit, overlap and scale of the fields of one report.
void check_report(const std::string& report, std::size_t length, const std::vector<Named>& fields,
                  std::vector<std::string>& errors) {
  const std::size_t before = errors.size();
  if (length == 0 || length > kMaxReportData) {
    errors.push_back(report + ".length: must be 1.." + std::to_string(kMaxReportData) +
                     " data bytes, got " + std::to_string(length));
    return;
  }
  for (const Named& n : fields) check_shape(n.where, *n.field, errors);
  if (errors.size() != before) return;  // the rest reads the fields' bits
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const FieldSpec& f = *fields[i].field;
    if (f.end() > length) {
      errors.push_back(fields[i].where + ": " + bytes_text(f) + " lie past the report's " +
                       std::to_string(length) + " data bytes");
    }
    if (!std::isfinite(f.scale) || f.scale == 0.0 || !std::isfinite(f.offset)) {
      errors.push_back(fields[i].where + ": scale must be finite and non-zero, offset finite");
    }
    for (std::size_t j = 0; j < i; ++j) {
      const FieldSpec& g = *fields[j].field;
      if (overlap(f, g)) {
        errors.push_back(fields[i].where + ": " + bytes_text(f) + " overlap " + fields[j].where +
                         " (" + bytes_text(g) + ")");
      }
    }
  }
}

void require_integer(const std::string& where, const FieldSpec& f, bool is_unsigned,
                     std::vector<std::string>& errors) {
  if (!is_integer(f) || (is_unsigned && counter_modulus(f) == 0)) {
    errors.push_back(
        where + ": type must be " +
        (is_unsigned ? "an unsigned integer (u8, u16, u32, or bits: N)" : "an integer") + ", got " +
        type_name(f));
  }
}

// A value the field holds exactly. A float must be one too: 0.1 would be sent as
// 0.100000001, which the device does not compare equal to the configured on value.
bool raw_fits(double raw, const FieldSpec& f) {
  return std::isfinite(raw) && raw >= raw_min(f) && raw <= raw_max(f) &&
         (is_integer(f) ? raw == std::floor(raw)
                        : static_cast<double>(static_cast<float>(raw)) == raw);
}

void check_force(const std::string& key, const FieldSpec& f, double full_scale, double max_force,
                 std::vector<std::string>& errors) {
  // A raw value itself: a fractional limit of an integer field rounds past it (127.5 -> 128).
  if (!raw_fits(full_scale, f) || full_scale <= 0.0) {
    errors.push_back(key + ".full_scale: must be > 0 and fit the field's type " + type_name(f) +
                     " (" + (is_integer(f) ? "whole counts, " : "") + "at most " + num(raw_max(f)) +
                     "), got " + num(full_scale));
    return;
  }
  const double lo_raw = std::max(-full_scale, raw_min(f));
  const double a = lo_raw * f.scale + f.offset;
  const double b = full_scale * f.scale + f.offset;
  const double lo = std::min(a, b), hi = std::max(a, b);
  // A scale so large that full scale is no finite force: +-inf would decode as inf.
  if (!std::isfinite(lo) || !std::isfinite(hi)) {
    errors.push_back(key + ": counts " + num(lo_raw) + ".." + num(full_scale) + " x " +
                     num(f.scale) +
                     " N is no finite force; use a scale that makes full_scale "
                     "a force in newtons");
    return;
  }
  if (lo > -max_force || hi < max_force) {
    errors.push_back(key + ": counts " + num(lo_raw) + ".." + num(full_scale) + " x " +
                     num(f.scale) + " N + " + num(f.offset) + " N reach only " + num(lo) + ".." +
                     num(hi) + " N, which cannot represent device.max_force +-" + num(max_force) +
                     " N");
  }
}

void check_switch(const std::string& where, const FieldSpec& f, double on, double off, bool has_off,
                  std::vector<std::string>& errors) {
  if (!raw_fits(on, f) || (has_off && !raw_fits(off, f))) {
    errors.push_back(where + ": on/off values must be raw values of type " + type_name(f));
  } else if (has_off && on == off) {
    errors.push_back(where + ": on and off must differ");
  }
}

void check_feature(const std::string& where, const FeatureLayout& fl, bool is_switch,
                   std::vector<std::string>& errors) {
  check_report(where, fl.length, {{where + ".field", &fl.field}}, errors);
  check_switch(where, fl.field, fl.on, fl.off, is_switch, errors);
}

void check_input(const InputLayout& in, std::vector<std::string>& errors) {
  std::vector<std::string> keys;
  for (std::size_t j = 0; j < in.joints(); ++j) keys.push_back(in.key(j));
  std::vector<Named> fields{{keys[0], &in.position}};
  for (std::size_t j = 1; j < in.joints(); ++j) {
    fields.push_back({keys[j], &in.more_positions[j - 1].field});
  }
  if (in.sequence) {
    fields.push_back({"input.sequence", &*in.sequence});
    require_integer("input.sequence", *in.sequence, true, errors);
  }
  if (in.status) {
    fields.push_back({"input.status", &*in.status});
    require_integer("input.status", *in.status, false, errors);
    const std::size_t bits = in.status->bits;
    if (bits < 32 && (in.fault_mask >> bits) != 0) {
      errors.push_back("input.status.fault_mask: has bits beyond the field's " +
                       std::to_string(bits));
    }
  }
  if (in.velocity) fields.push_back({"input.velocity", &*in.velocity});
  check_report("input", in.length, fields, errors);
  for (std::size_t j = 0; j < in.joints(); ++j) {
    if (in.joint(j).wraps && !is_integer(in.joint(j).field)) {
      errors.push_back(keys[j] + ".wraps: only an integer field wraps (this one is f32)");
    }
  }
  if (in.velocity && in.joints() > 1) {
    errors.push_back("input.velocity: one field for " + std::to_string(in.joints()) +
                     " joints: a device's velocity is read for a one-joint mechanism only");
  }
}

}  // namespace

std::string InputLayout::key(std::size_t j) const {
  return listed ? "input.positions[" + std::to_string(j) + "]" : "input.position";
}

std::string OutputLayout::key(std::size_t j) const {
  return listed ? "output.forces[" + std::to_string(j) + "]" : "output.force";
}

std::vector<std::string> validate(const ReportProfileLayout& l, std::span<const double> max_force) {
  std::vector<std::string> errors;
  check_input(l.input, errors);
  const OutputLayout& o = l.output;
  std::vector<std::string> keys;
  for (std::size_t j = 0; j < o.joints(); ++j) keys.push_back(o.key(j));
  std::vector<Named> out{{keys[0], &o.force}};
  for (std::size_t j = 1; j < o.joints(); ++j)
    out.push_back({keys[j], &o.more_forces[j - 1].field});
  if (o.enable) {
    out.push_back({"output.enable", &o.enable->field});
    check_switch("output.enable", o.enable->field, o.enable->on, o.enable->off, true, errors);
  }
  if (o.keepalive) {
    out.push_back({"output.keepalive", &*o.keepalive});
    require_integer("output.keepalive", *o.keepalive, true, errors);
    if (o.keepalive->bits == 1) {
      errors.push_back(
          "output.keepalive: one bit cannot both differ from the output-off report's 0 and "
          "change with every report: give it 2 bits or more");
    }
  }
  check_report("output", o.length, out, errors);
  for (std::size_t j = 0; j < o.joints(); ++j) {
    const double need = j < max_force.size() ? max_force[j] : max_force.back();
    check_force(keys[j], o.joint(j).field, o.joint(j).full_scale, need, errors);
  }
  if (!o.enable && !l.enable_feature) {
    errors.push_back(
        "output: needs an enable field or an enable_feature report, so the "
        "amplifier is off until the loop enables it");
  }
  std::vector<const FeatureLayout*> features;
  const auto feature = [&](const std::optional<FeatureLayout>& f, const char* name, bool sw) {
    if (!f) return;
    check_feature(name, *f, sw, errors);
    for (const FeatureLayout* g : features) {
      if (g->report_id == f->report_id) {
        errors.push_back(std::string(name) + ".report_id: " + std::to_string(f->report_id) +
                         " is already another feature report's id");
      }
    }
    features.push_back(&*f);
  };
  feature(l.enable_feature, "enable_feature", true);
  feature(l.gain_feature, "gain_feature", false);
  feature(l.watchdog_feature, "watchdog_feature", false);
  const bool numbered = l.input.report_id != 0;
  const auto same_numbering = [&](std::uint8_t id, const char* where) {
    if ((id != 0) != numbered) {
      errors.push_back(std::string(where) +
                       ".report_id: a device numbers all its reports or none (input.report_id "
                       "is " +
                       std::to_string(l.input.report_id) + ", this is " + std::to_string(id) + ")");
    }
  };
  same_numbering(o.report_id, "output");
  for (const FeatureLayout* f : features) {
    same_numbering(f->report_id, f == &*l.enable_feature ? "enable_feature"
                                 : f == &*l.gain_feature ? "gain_feature"
                                                         : "watchdog_feature");
  }
  return errors;
}

std::vector<std::string> validate(const ReportProfileLayout& layout, double max_force) {
  return validate(layout, std::span<const double>(&max_force, 1));
}

std::size_t input_report_size(const InputLayout& layout) noexcept {
  return layout.length + (layout.report_id != 0 ? 1 : 0);
}

InputDecode decode_input(std::span<const std::uint8_t> report, const InputLayout& layout,
                         InputValues& out) noexcept {
  if (report.empty()) return InputDecode::kEmpty;
  const bool numbered = layout.report_id != 0;
  if (numbered && report[0] != layout.report_id) return InputDecode::kOtherReport;
  const std::span<const std::uint8_t> data = numbered ? report.subspan(1) : report;
  if (data.size() < layout.length) return InputDecode::kTooShort;
  for (std::size_t j = 0; j < layout.joints(); ++j) {
    const FieldSpec& f = j == 0 ? layout.position : layout.more_positions[j - 1].field;
    out.position[j] = read_si(data.data(), f);
    out.position_count[j] = read_count(data.data(), f);
  }
  if (layout.sequence) {
    out.sequence = static_cast<std::uint32_t>(read_count(data.data(), *layout.sequence));
  }
  if (layout.status) {
    out.status = static_cast<std::uint32_t>(read_count(data.data(), *layout.status));
  }
  if (layout.velocity) out.velocity = read_si(data.data(), *layout.velocity);
  return InputDecode::kOk;
}

void encode_input(const InputValues& in, const InputLayout& layout,
                  std::span<std::uint8_t> report) noexcept {
  std::fill(report.begin(), report.end(), std::uint8_t{0});
  std::uint8_t* data = report.data();
  if (layout.report_id != 0) *data++ = layout.report_id;
  for (std::size_t j = 0; j < layout.joints(); ++j) {
    const PositionField p = layout.joint(j);
    const double count = std::nearbyint(si_to_raw(in.position[j], p.field));
    if (p.wraps && std::isfinite(count) && std::abs(count) < 0x1p62) {
      write_wrapped(data, p.field, static_cast<std::int64_t>(count));  // a multi-turn axis
    } else {
      write_si(data, p.field, in.position[j]);
    }
  }
  if (layout.sequence) write_wrapped(data, *layout.sequence, in.sequence);
  if (layout.status) write_raw(data, *layout.status, static_cast<double>(in.status));
  if (layout.velocity) write_si(data, *layout.velocity, in.velocity);
}

void encode_force(std::span<const double> forces, const OutputLayout& layout,
                  std::span<std::uint8_t> report) noexcept {
  for (std::size_t j = 0; j < layout.joints() && j < forces.size(); ++j) {
    const FieldSpec& f = j == 0 ? layout.force : layout.more_forces[j - 1].field;
    const double fs = j == 0 ? layout.full_scale : layout.more_forces[j - 1].full_scale;
    write_raw(report.data() + 1, f, std::clamp(si_to_raw(forces[j], f), -fs, fs));
  }
}

bool decode_output(std::span<const std::uint8_t> report, const OutputLayout& layout,
                   OutputValues& out) noexcept {
  if (report.size() < wire_size(layout.length) || report[0] != layout.report_id) return false;
  const std::uint8_t* data = report.data() + 1;
  for (std::size_t j = 0; j < layout.joints(); ++j) {
    const ForceField f = layout.joint(j);
    out.force[j] =
        std::clamp(read_raw(data, f.field), -f.full_scale, f.full_scale) * f.field.scale +
        f.field.offset;
  }
  out.enable = true;
  if (layout.enable) out.enable = read_raw(data, layout.enable->field) == layout.enable->on;
  if (layout.keepalive) out.keepalive = read_raw(data, *layout.keepalive);
  return true;
}

void encode_feature(double raw, const FeatureLayout& layout,
                    std::span<std::uint8_t> report) noexcept {
  std::fill(report.begin(), report.end(), std::uint8_t{0});
  report[0] = layout.report_id;
  write_raw(report.data() + 1, layout.field, raw);
}

std::optional<double> decode_feature(std::span<const std::uint8_t> report,
                                     const FeatureLayout& layout) noexcept {
  if (report.size() < wire_size(layout.length) || report[0] != layout.report_id) {
    return std::nullopt;
  }
  return read_raw(report.data() + 1, layout.field);
}

}  // namespace hapticd::drivers::hid
