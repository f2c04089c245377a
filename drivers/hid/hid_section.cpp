#include "drivers/hid/hid_settings.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "drivers/field/field_schema.h"
#include "drivers/hid/hid_section_reading.h"
#include "kinematics/kinematics.h"

namespace hapticd::drivers::hid {
namespace section {

void Ctx::error_at(const std::string& rel, const std::string& what, const YAML::Mark& fallback) {
  YAML::Mark m = fallback;
  std::size_t best = 0;
  for (const auto& [path, mark] : marks) {
    if (rel.compare(0, path.size(), path) == 0 && path.size() >= best &&
        (rel.size() == path.size() || rel[path.size()] == '.')) {
      best = path.size();
      m = mark;
    }
  }
  d.error(m, "device.hid.report." + rel, what);
}

Field take(MapReader& m, const char* key, const char* why) {
  const Field f = m.take(key);
  if (!f.present && why != nullptr) m.missing(key, why);
  return f;
}

void raw_value(MapReader& m, const Field& f, double& out) {
  const bool hex = f.present && f.node.IsScalar() && f.node.Scalar().size() > 2 &&
                   f.node.Scalar()[0] == '0' && (f.node.Scalar()[1] | 0x20) == 'x';
  if (!hex) return number(m, f, Range::any(), out);
  if (const auto v = read_hex(m.diag(), f, 0xFFFFFFFFu)) out = static_cast<double>(*v);
}

FieldSpec read_spec(MapReader& m, bool quantity) {
  return field::read_spec(m, kMaxReportData - 1, quantity);
}

bool absent(const Field& f) { return !f.present || f.node.IsNull(); }

std::optional<FieldSpec> optional_field(MapReader& parent, Ctx& c, const std::string& rel,
                                        const char* key, bool quantity) {
  const Field field = parent.take(key);
  if (absent(field)) return std::nullopt;
  c.mark(field, rel + "." + key);
  MapReader m(c.d, field);
  FieldSpec f = read_spec(m, quantity);
  m.finish();
  return f;
}

}  // namespace section

namespace {

using namespace section;

// {usage_page, usage} -> page << 16 | usage.
std::optional<std::uint32_t> read_usage(MapReader& m, Ctx& c) {
  const auto page = read_hex(c.d, take(m, "usage_page", "the usage page (e.g. 0x01)"), 0xFFFF);
  const auto id = read_hex(c.d, take(m, "usage", "the usage (e.g. 0x30 for X)"), 0xFFFF);
  if (!page || !id) return std::nullopt;
  return usage(static_cast<std::uint16_t>(*page), static_cast<std::uint16_t>(*id));
}

// One entry of `position` / `positions`: {usage_page, usage, min, max}.
PidPosition read_pid_position(Ctx& c, const Field& f) {
  PidPosition p;
  MapReader pm(c.d, f);
  if (const auto u = read_usage(pm, c)) p.usage = *u;
  number(pm, take(pm, "min", "the position (m or rad) at the axis' logical minimum"), Range::any(),
         p.min);
  number(pm, take(pm, "max", "the position at its logical maximum"), Range::any(), p.max);
  pm.finish();
  if (p.min == p.max && !c.failed()) c.d.error(f.key_mark, f.path, "min and max must differ");
  return p;
}

// The positions, one per joint of the mechanism; two joints need their effects' Directions.
void read_pid_axes(MapReader& m, Ctx& c, const Field& pid, int joints, PidSettings& p) {
  bool listed = false;
  for (const Field& f : joint_fields(m, c, "position", "positions", "pid",
                                     "{usage_page, usage, min, max}", listed)) {
    const PidPosition pos = read_pid_position(c, f);
    if (!p.positions.empty() && pos.usage == p.positions.front().usage && !c.failed()) {
      c.d.error(f.key_mark, f.path,
                "the same usage as positions[0]: each joint reads its own axis");
    }
    p.positions.push_back(pos);
  }
  const Field dirs = m.take("directions_deg");
  if (joints > 2) {
    c.d.error(pid.key_mark, pid.path,
              "drives one or two joints (X and Y), the mechanism has " + std::to_string(joints) +
                  " (device.kinematics); profile report drives several");
  } else if (!p.positions.empty() && p.joints() != static_cast<std::size_t>(joints)) {
    c.d.error(pid.key_mark, pid.path + (listed ? ".positions" : ".position"),
              std::to_string(p.joints()) + " position(s) for a mechanism of " +
                  std::to_string(joints) + " joint(s) (device.kinematics)");
  }
  if (joints == 1) {
    if (!absent(dirs)) {
      c.d.error(dirs.key_mark, dirs.path,
                "two joints' only: one joint's effect has one polar direction_deg");
    }
    number(m, m.take("direction_deg"), Range::interval(0.0, true, 360.0, false), p.direction_deg);
    return;
  }
  if (const Field one = m.take("direction_deg"); !absent(one)) {
    c.d.error(one.key_mark, one.path,
              "one joint's only: two joints' effects each have their own entry of directions_deg");
  }
  if (absent(dirs)) {
    m.missing("directions_deg",
              "each joint's effect's Direction (which way the firmware turns a positive "
              "Magnitude is a fact of the firmware: docs/drivers/hid.md, \"Two axes\")");
    return;
  }
  if (!dirs.node.IsSequence() || dirs.node.size() != 2) {
    c.d.error(dirs.key_mark, dirs.path,
              "must be a list of 2 directions (degrees), joint i's effect's being entry i, got " +
                  config::schema::describe_value(dirs.node));
    return;
  }
  for (std::size_t i = 0; i < 2; ++i) {
    double d = 0.0;
    const Field e{dirs.path + "[" + std::to_string(i) + "]", dirs.node[i], dirs.node[i].Mark(),
                  true};
    number(m, e, Range::interval(0.0, true, 360.0, true), d);
    p.directions_deg.push_back(d);
  }
}

// The force reports of a tick go out one a polling interval: they must fit the period.
void check_pid_rate(Ctx& c, const Field& pid, const config::Config& cfg, const HidSettings& s) {
  // One report a tick faster than the polling (a 2 kHz loop over 1 ms polling) is the queue's
  // and the declared delay's, as it always was; several must fit.
  const double n = static_cast<double>(force_reports_per_tick(s));
  const double period_ms = 1e3 * cfg.loop.sample_period_s();
  if (n < 2 || n * s.poll_interval_ms <= period_ms + 1e-9) return;
  using config::schema::format_number;
  c.d.error(pid.key_mark, pid.path + ".positions",
            format_number(n) + " joints send " + format_number(n) +
                " Set Constant Force reports a period, one a polling interval (poll_interval_ms " +
                format_number(s.poll_interval_ms) + "): they need " +
                format_number(n * s.poll_interval_ms) + " ms, the period is " +
                format_number(period_ms) + " ms; lower loop.rate_hz to at most " +
                format_number(std::floor(1e3 / (n * s.poll_interval_ms))));
}

void read_pid_profile(MapReader& hid, Ctx& c, const config::Config& cfg, HidSettings& s) {
  const Field field = take(hid, "pid", "the PID settings (profile pid)");
  const int joints = kinematics::joint_count(cfg.device.kinematics);
  MapReader m(c.d, field);
  PidSettings& p = s.pid;
  read_pid_axes(m, c, field, joints, p);
  const Field seq = m.take("sequence");
  if (!absent(seq)) {
    MapReader sm(c.d, seq);
    if (const auto u = read_usage(sm, c)) p.sequence_usage = *u;
    sm.finish();
  }
  const Field fs = take(m, "force_full_scale", "the force (N) at the Magnitude's logical maximum");
  number(m, fs, Range::greater_than(0.0), p.force_full_scale);
  double max_force = 0.0;
  for (int j = 0; j < std::max(1, joints); ++j) {
    max_force = std::max(max_force, cfg.device.max_force[static_cast<std::size_t>(j)]);
  }
  if (fs.present && p.force_full_scale > 0.0 && p.force_full_scale < max_force) {
    c.d.error(fs.key_mark, fs.path,
              "cannot represent device.max_force " + config::schema::format_number(max_force) +
                  " N: the magnitude saturates at " +
                  config::schema::format_number(p.force_full_scale) + " N");
  }
  number(m, m.take("gain"), Range::interval(0.0, false, 1.0, true), p.gain);
  const Field dur = m.take("effect_duration_ms");
  number(m, dur, Range::interval(0.0, true, 32767.0, true), p.effect_duration_ms);
  // Each of the effects is restarted in turn, one a tick, every half duration.
  const double effects = static_cast<double>(std::max<std::size_t>(1, p.joints()));
  const double min_ms = 2e3 * effects * cfg.loop.sample_period_s();
  if (dur.present && p.effect_duration_ms > 0.0 && p.effect_duration_ms < min_ms) {
    c.d.error(dur.key_mark, dur.path,
              std::string("must be 0 (infinite) or at least ") + (effects == 1 ? "two" : "four") +
                  " sample periods (" + config::schema::format_number(min_ms) +
                  " ms): the driver restarts each effect every half duration");
  }
  if (const auto v = read_hex(c.d, m.take("fault_mask"), 0xFF)) p.fault_mask = *v;
  m.finish();
  if (!c.failed()) check_pid_rate(c, field, cfg, s);  // after poll_interval_ms
}

void read_select(MapReader& hid, Ctx& c, Selector& sel) {
  const Field field = take(hid, "select", "which device: vendor_id/product_id, serial, path...");
  MapReader m(c.d, field);
  if (const auto v = read_hex(c.d, m.take("vendor_id"), 0xFFFF))
    sel.vendor_id = static_cast<std::uint16_t>(*v);
  if (const auto v = read_hex(c.d, m.take("product_id"), 0xFFFF))
    sel.product_id = static_cast<std::uint16_t>(*v);
  if (const auto v = config::schema::read_string(c.d, m.take("serial"))) sel.serial = *v;
  int interface = -1;
  integer(m, m.take("interface"), IntRange::between(-1, 255), interface);
  if (interface >= 0) sel.interface = interface;
  if (const auto v = read_hex(c.d, m.take("usage_page"), 0xFFFF))
    sel.usage_page = static_cast<std::uint16_t>(*v);
  if (const auto v = read_hex(c.d, m.take("usage"), 0xFFFF))
    sel.usage = static_cast<std::uint16_t>(*v);
  if (const auto v = config::schema::read_string(c.d, m.take("path"))) sel.path = *v;
  m.finish();
  if (field.present && !sel.vendor_id && !sel.product_id && sel.serial.empty() &&
      sel.path.empty() && !sel.usage_page) {
    c.d.error(field.key_mark, field.path,
              "selects every HID device: give vendor_id and product_id, a serial, a usage_page "
              "or a path (`hapticd devices` lists what is attached)");
  }
}

void read_limits(MapReader& hid, Ctx& c, Limits& l) {
  const Field field = hid.take("limits");
  MapReader m(c.d, field);
  integer(m, m.take("out_queue"), IntRange::between(1, 64), l.out_queue);
  integer(m, m.take("out_queue_full_fault"), IntRange::between(1, 1000000), l.out_queue_full_fault);
  number(m, m.take("timeout_ms"), Range::interval(0.0, false, 60000.0, true), l.timeout_ms);
  m.finish();
}

// reports_on_change and its liveness bound: longer than the device's own resend interval
// (OpenFFBoard: about 100 report intervals), and meaningless for a device that reports every
// period (the loop's stale check is its bound).
void read_liveness(MapReader& hid, Ctx& c, const config::Config& cfg, HidSettings& s) {
  if (const auto v = config::schema::read_bool(c.d, hid.take("reports_on_change")))
    s.reports_on_change = *v;
  const Field live = hid.take("liveness_ms");
  const double min_ms = 2e3 * cfg.loop.sample_period_s();
  number(hid, live, Range::interval(0.0, false, 60000.0, true), s.liveness_ms);
  if (!live.present) return;
  if (!s.reports_on_change) {
    c.d.error(live.key_mark, live.path,
              "only with reports_on_change: true (a device that reports every period is "
              "bounded by safety.stale_fault_ticks)");
  } else if (s.liveness_ms < min_ms) {
    c.d.error(
        live.key_mark, live.path,
        "must be at least two sample periods (" + config::schema::format_number(min_ms) + " ms)");
  }
}

}  // namespace

std::shared_ptr<const config::DriverSettings> read_hid_section(MapReader& hid,
                                                               const config::Config& cfg) {
  Ctx c{hid.diag(), {}, hid.diag().messages().size()};
  auto s = std::make_shared<HidSettings>();
  read_select(hid, c, s->select);
  if (const auto b = config::schema::read_choice(c.d, hid.take("backend"), {"hidraw", "libusb"})) {
    s->backend = *b == 0 ? Backend::kHidraw : Backend::kLibusb;
  }
  if (const auto p = config::schema::read_choice(c.d, take(hid, "profile", "report or pid"),
                                                 {"report", "pid"})) {
    s->profile = *p == 0 ? Profile::kReport : Profile::kPid;
  }
  number(hid, hid.take("poll_interval_ms"), Range::interval(0.0, false, 1000.0, true),
         s->poll_interval_ms);
  read_limits(hid, c, s->limits);
  read_liveness(hid, c, cfg, *s);
  if (s->profile == Profile::kReport) {
    read_report_profile(hid, c, cfg, *s);
    hid.not_used("pid", "profile report");
  } else {
    read_pid_profile(hid, c, cfg, *s);
    hid.not_used("report", "profile pid");
  }
  s->writer_priority = std::max(1, cfg.loop.rt_priority - 1);
  if (c.failed()) return nullptr;
  return s;
}

}  // namespace hapticd::drivers::hid
