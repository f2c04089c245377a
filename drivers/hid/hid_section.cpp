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

void read_pid_profile(MapReader& hid, Ctx& c, const config::Config& cfg, HidSettings& s) {
  const Field field = take(hid, "pid", "the PID settings (profile pid)");
  if (const int joints = kinematics::joint_count(cfg.device.kinematics); joints != 1) {
    c.d.error(field.key_mark, field.path,
              "drives one joint, the mechanism has " + std::to_string(joints) +
                  " (device.kinematics): a PID device of several axes is not supported yet "
                  "(docs/drivers/hid.md, \"Two axes\"); profile report drives several");
  }
  MapReader m(c.d, field);
  PidSettings& p = s.pid;
  const Field pos = take(m, "position", "{usage_page, usage, min, max}");
  MapReader pm(c.d, pos);
  if (const auto u = read_usage(pm, c)) p.position_usage = *u;
  number(pm, take(pm, "min", "the position (m or rad) at the axis' logical minimum"), Range::any(),
         p.position_min);
  number(pm, take(pm, "max", "the position at its logical maximum"), Range::any(), p.position_max);
  pm.finish();
  if (pos.present && p.position_min == p.position_max && !c.failed()) {
    c.d.error(pos.key_mark, pos.path, "min and max must differ");
  }
  const Field seq = m.take("sequence");
  if (!absent(seq)) {
    MapReader sm(c.d, seq);
    if (const auto u = read_usage(sm, c)) p.sequence_usage = *u;
    sm.finish();
  }
  const Field fs = take(m, "force_full_scale", "the force (N) at the Magnitude's logical maximum");
  number(m, fs, Range::greater_than(0.0), p.force_full_scale);
  if (fs.present && p.force_full_scale > 0.0 && p.force_full_scale < cfg.device.max_force[0]) {
    c.d.error(fs.key_mark, fs.path,
              "cannot represent device.max_force " +
                  config::schema::format_number(cfg.device.max_force[0]) +
                  " N: the magnitude saturates at " +
                  config::schema::format_number(p.force_full_scale) + " N");
  }
  number(m, m.take("gain"), Range::interval(0.0, false, 1.0, true), p.gain);
  number(m, m.take("direction_deg"), Range::interval(0.0, true, 360.0, false), p.direction_deg);
  const Field dur = m.take("effect_duration_ms");
  number(m, dur, Range::interval(0.0, true, 32767.0, true), p.effect_duration_ms);
  const double two_periods_ms = 2e3 * cfg.loop.sample_period_s();
  if (dur.present && p.effect_duration_ms > 0.0 && p.effect_duration_ms < two_periods_ms) {
    c.d.error(dur.key_mark, dur.path,
              "must be 0 (infinite) or at least two sample periods (" +
                  config::schema::format_number(two_periods_ms) +
                  " ms): the driver restarts it every half duration");
  }
  if (const auto v = read_hex(c.d, m.take("fault_mask"), 0xFF)) p.fault_mask = *v;
  m.finish();
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
