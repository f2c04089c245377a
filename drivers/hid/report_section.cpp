// device.hid.report: the profile report's layout, one position and one force field per joint
// (docs/drivers/hid.md), each mistake at its key.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "drivers/hid/hid_section_reading.h"
#include "kinematics/kinematics.h"

namespace hapticd::drivers::hid::section {

namespace {

std::string at(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

}  // namespace

// The entries of a list form (`positions`, `forces`): one mapping per joint, joint i entry i.
// Nothing for a list that is not one of 1..kMaxJoints entries (reported at its key).
std::vector<Field> list_entries(Ctx& c, const Field& f, const std::string& rel) {
  c.mark(f, rel);
  if (!f.node.IsSequence() || f.node.size() == 0 || f.node.size() > base::kMaxJoints) {
    c.d.error(f.key_mark, f.path,
              "must be a list of 1 to " + std::to_string(base::kMaxJoints) +
                  " fields, joint i being entry i, got " + config::schema::describe_value(f.node));
    return {};
  }
  std::vector<Field> out;
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    out.push_back(Field{at(f.path, i), f.node[i], f.node[i].Mark(), true});
    c.marks[at(rel, i)] = f.node[i].Mark();
  }
  return out;
}

// The one-joint key or its list form, never both: which one names the joints' fields.
// `listed`: the list form was given.
std::vector<Field> joint_fields(MapReader& m, Ctx& c, const char* one, const char* list,
                                const std::string& parent, const char* why, bool& listed) {
  const Field single = m.take(one);
  const Field many = m.take(list);
  listed = !absent(many);
  if (!absent(single) && !absent(many)) {
    c.d.error(
        many.key_mark, many.path,
        std::string("give ") + one + " (one joint) or " + list + " (one per joint), not both");
    return {};
  }
  if (!absent(many)) return list_entries(c, many, parent + "." + list);
  if (absent(single)) {
    m.missing(one, why);
    return {};
  }
  c.mark(single, parent + "." + one);
  return {single};
}

namespace {

// The keys every report starts with: its id and its data length.
void read_report_head(MapReader& m, Ctx& c, std::uint8_t& report_id, std::size_t& length) {
  if (const auto v = read_hex(c.d, m.take("report_id"), 255))
    report_id = static_cast<std::uint8_t>(*v);
  integer(m, take(m, "length", "data bytes after the report id"),
          IntRange::between(1, kMaxReportData), length);
}

PositionField read_position(Ctx& c, const Field& f, const std::string& rel) {
  MapReader p(c.d, f);
  PositionField out{read_spec(p, true), false};
  const Field wraps = p.take("wraps");
  c.mark(wraps, rel + ".wraps");
  if (const auto w = config::schema::read_bool(c.d, wraps)) out.wraps = *w;
  p.finish();
  return out;
}

void read_input(MapReader& report, Ctx& c, InputLayout& in) {
  const Field field = take(report, "input", "the input report with the position");
  c.mark(field, "input");
  MapReader m(c.d, field);
  read_report_head(m, c, in.report_id, in.length);
  const std::vector<Field> fields =
      joint_fields(m, c, "position", "positions", "input", "where the position is", in.listed);
  for (std::size_t j = 0; j < fields.size(); ++j) {
    const PositionField p = read_position(c, fields[j], in.key(j));
    if (j == 0) {
      in.position = p.field;
      in.position_wraps = p.wraps;
    } else {
      in.more_positions.push_back(p);
    }
  }
  in.sequence = optional_field(m, c, "input", "sequence", false);
  const Field status = m.take("status");
  if (!absent(status)) {
    c.mark(status, "input.status");
    MapReader s(c.d, status);
    in.status = read_spec(s, false);
    if (const auto v = read_hex(c.d, s.take("fault_mask"), 0xFFFFFFFFu)) in.fault_mask = *v;
    s.finish();
  }
  in.velocity = optional_field(m, c, "input", "velocity", true);
  m.finish();
}

ForceField read_force(Ctx& c, const Field& f) {
  MapReader m(c.d, f);
  ForceField out{read_spec(m, true), 0.0};
  number(m, take(m, "full_scale", "the largest |raw| force the device accepts"),
         Range::greater_than(0.0), out.full_scale);
  m.finish();
  return out;
}

void read_output(MapReader& report, Ctx& c, OutputLayout& out) {
  const Field field = take(report, "output", "the output report with the force");
  c.mark(field, "output");
  MapReader m(c.d, field);
  read_report_head(m, c, out.report_id, out.length);
  const std::vector<Field> fields =
      joint_fields(m, c, "force", "forces", "output", "where the force command goes", out.listed);
  for (std::size_t j = 0; j < fields.size(); ++j) {
    const ForceField f = read_force(c, fields[j]);
    if (j == 0) {
      out.force = f.field;
      out.full_scale = f.full_scale;
    } else {
      out.more_forces.push_back(f);
    }
  }
  const Field enable = m.take("enable");
  if (!absent(enable)) {
    c.mark(enable, "output.enable");
    MapReader e(c.d, enable);
    SwitchField sw{read_spec(e, false)};
    raw_value(e, e.take("on"), sw.on);
    raw_value(e, e.take("off"), sw.off);
    e.finish();
    out.enable = sw;
  }
  out.keepalive = optional_field(m, c, "output", "keepalive", false);
  m.finish();
}

// A feature report: report_id, length, field, and on/off (enable) or value.
std::optional<FeatureLayout> read_feature(MapReader& report, Ctx& c, const char* key,
                                          bool is_switch) {
  const Field field = report.take(key);
  if (absent(field)) return std::nullopt;
  c.mark(field, key);
  MapReader m(c.d, field);
  FeatureLayout f;
  if (const auto v = read_hex(c.d, take(m, "report_id", "the feature report's id"), 255)) {
    f.report_id = static_cast<std::uint8_t>(*v);
  }
  integer(m, take(m, "length", "data bytes after the report id"),
          IntRange::between(1, kMaxReportData), f.length);
  const Field spec = take(m, "field", "where the value goes: {byte, type, endian}");
  c.mark(spec, std::string(key) + ".field");
  MapReader s(c.d, spec);
  f.field = read_spec(s, false);
  s.finish();
  if (is_switch) {
    raw_value(m, m.take("on"), f.on);
    raw_value(m, m.take("off"), f.off);
  } else {
    raw_value(m, take(m, "value", "the raw value written"), f.on);
  }
  m.finish();
  return f;
}

// A wrapping position is unwrapped the short way round (drivers/io/counter_unwrap.h): half the
// field's range must be more than the loop lets the axis move in one period, or a real move
// could be taken the other way round before the speed check could see it.
void check_wrap(Ctx& c, const config::Config& cfg, const InputLayout& in, const YAML::Mark& at) {
  for (std::size_t j = 0; j < in.joints(); ++j) {
    const PositionField p = in.joint(j);
    if (!p.wraps) continue;
    const double half = std::ldexp(std::abs(p.field.scale), static_cast<int>(p.field.bits) - 1);
    const double step = cfg.safety.max_speed * cfg.loop.sample_period_s();
    if (half > step) continue;
    c.error_at(in.key(j) + ".wraps",
               "a " + std::to_string(p.field.bits) + "-bit position of " +
                   config::schema::format_number(p.field.scale) + " per count wraps every " +
                   config::schema::format_number(2.0 * half) +
                   ": a move of half that in one period cannot be told from one the other way, "
                   "and safety.max_speed allows " +
                   config::schema::format_number(step) + " a period",
               at);
  }
}

// One position and one force field per joint of device.kinematics, joint i entry i.
void check_joints(Ctx& c, const config::Config& cfg, const ReportProfileLayout& l,
                  const YAML::Mark& at) {
  const auto joints = static_cast<std::size_t>(kinematics::joint_count(cfg.device.kinematics));
  const auto check = [&](std::size_t n, bool listed, const char* one, const char* list) {
    if (n == joints) return;
    c.error_at(listed ? list : one,
               std::to_string(n) + " field(s) for a mechanism of " + std::to_string(joints) +
                   " joint(s) (device.kinematics): give " + list +
                   ", one per joint, joint i is entry i",
               at);
  };
  check(l.input.joints(), l.input.listed, "input.position", "input.positions");
  check(l.output.joints(), l.output.listed, "output.force", "output.forces");
}

}  // namespace

void read_report_profile(MapReader& hid, Ctx& c, const config::Config& cfg, HidSettings& s) {
  const Field field = take(hid, "report", "the report layout (profile report)");
  MapReader m(c.d, field);
  ReportProfileLayout& l = s.report;
  read_input(m, c, l.input);
  read_output(m, c, l.output);
  l.enable_feature = read_feature(m, c, "enable_feature", true);
  l.gain_feature = read_feature(m, c, "gain_feature", false);
  l.watchdog_feature = read_feature(m, c, "watchdog_feature", false);
  m.finish();
  if (c.failed()) return;
  check_joints(c, cfg, l, field.key_mark);
  if (c.failed()) return;
  std::array<double, base::kMaxJoints> max_force{};
  for (std::size_t j = 0; j < max_force.size(); ++j) max_force[j] = cfg.device.max_force[j];
  for (const std::string& e : validate(l, max_force)) {
    const std::size_t colon = e.find(": ");
    c.error_at(e.substr(0, colon), e.substr(colon + 2), field.key_mark);
  }
  check_wrap(c, cfg, l.input, field.key_mark);
}

}  // namespace hapticd::drivers::hid::section
