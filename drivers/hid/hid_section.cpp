#include "drivers/hid/hid_settings.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "drivers/field/field_schema.h"

namespace hapticd::drivers::hid {
namespace {

using config::schema::Diagnostics;
using config::schema::Field;
using config::schema::integer;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;
using config::schema::read_hex;

// Reading state shared by the helpers: where each sub-key is (for errors found after
// reading) and whether anything went wrong in this section.
struct Ctx {
  Diagnostics& d;
  std::map<std::string, YAML::Mark> marks;  // path below device.hid.report -> key mark
  std::size_t errors_before;
  bool failed() const { return d.messages().size() != errors_before; }
  void mark(const Field& f, const std::string& rel) {
    if (f.present) marks[rel] = f.key_mark;
  }
  // Reports "device.hid.report.<rel>: what" at the closest key recorded for `rel`.
  void error_at(const std::string& rel, const std::string& what, const YAML::Mark& fallback) {
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
};

// Takes `key`; reports it missing (with `why`) when `why` is given and it is absent.
Field take(MapReader& m, const char* key, const char* why = nullptr) {
  const Field f = m.take(key);
  if (!f.present && why != nullptr) m.missing(key, why);
  return f;
}

// A raw value written into a field (an enable's on/off, a feature's value): a number, or an
// unsigned integer in 0x hexadecimal as ids and masks are.
void raw_value(MapReader& m, const Field& f, double& out) {
  const bool hex = f.present && f.node.IsScalar() && f.node.Scalar().size() > 2 &&
                   f.node.Scalar()[0] == '0' && (f.node.Scalar()[1] | 0x20) == 'x';
  if (!hex) return number(m, f, Range::any(), out);
  if (const auto v = read_hex(m.diag(), f, 0xFFFFFFFFu)) out = static_cast<double>(*v);
}

// Where one field is and what it holds (drivers/field/field_schema.h).
FieldSpec read_spec(MapReader& m, bool quantity) {
  return field::read_spec(m, kMaxReportData - 1, quantity);
}

// A key given without a value (`--set device.hid.report.output.enable=`) is absent: that is
// how an optional mapping of an example file is removed from the command line.
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

// The keys every report starts with: its id and its data length.
void read_report_head(MapReader& m, Ctx& c, std::uint8_t& report_id, std::size_t& length) {
  if (const auto v = read_hex(c.d, m.take("report_id"), 255))
    report_id = static_cast<std::uint8_t>(*v);
  integer(m, take(m, "length", "data bytes after the report id"),
          IntRange::between(1, kMaxReportData), length);
}

void read_input(MapReader& report, Ctx& c, InputLayout& in) {
  const Field field = take(report, "input", "the input report with the position");
  c.mark(field, "input");
  MapReader m(c.d, field);
  read_report_head(m, c, in.report_id, in.length);
  const Field pos = take(m, "position", "where the position is");
  c.mark(pos, "input.position");
  MapReader p(c.d, pos);
  in.position = read_spec(p, true);
  const Field wraps = p.take("wraps");
  c.mark(wraps, "input.position.wraps");
  if (const auto w = config::schema::read_bool(c.d, wraps)) in.position_wraps = *w;
  p.finish();
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

void read_output(MapReader& report, Ctx& c, OutputLayout& out) {
  const Field field = take(report, "output", "the output report with the force");
  c.mark(field, "output");
  MapReader m(c.d, field);
  read_report_head(m, c, out.report_id, out.length);
  const Field force = take(m, "force", "where the force command goes");
  c.mark(force, "output.force");
  MapReader f(c.d, force);
  out.force = read_spec(f, true);
  number(f, take(f, "full_scale", "the largest |raw| force the device accepts"),
         Range::greater_than(0.0), out.full_scale);
  f.finish();
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
  if (!in.position_wraps) return;
  const double half =
      std::ldexp(std::abs(in.position.scale), static_cast<int>(in.position.bits) - 1);
  const double step = cfg.safety.max_speed * cfg.loop.sample_period_s();
  if (half > step) return;
  c.error_at("input.position.wraps",
             "a " + std::to_string(in.position.bits) + "-bit position of " +
                 config::schema::format_number(in.position.scale) + " per count wraps every " +
                 config::schema::format_number(2.0 * half) +
                 ": a move of half that in one period cannot be told from one the other way, and "
                 "safety.max_speed allows " +
                 config::schema::format_number(step) + " a period",
             at);
}

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
  for (const std::string& e : validate(l, cfg.device.max_force[0])) {
    const std::size_t colon = e.find(": ");
    c.error_at(e.substr(0, colon), e.substr(colon + 2), field.key_mark);
  }
  check_wrap(c, cfg, l.input, field.key_mark);
}

// {usage_page, usage} -> page << 16 | usage.
std::optional<std::uint32_t> read_usage(MapReader& m, Ctx& c) {
  const auto page = read_hex(c.d, take(m, "usage_page", "the usage page (e.g. 0x01)"), 0xFFFF);
  const auto id = read_hex(c.d, take(m, "usage", "the usage (e.g. 0x30 for X)"), 0xFFFF);
  if (!page || !id) return std::nullopt;
  return usage(static_cast<std::uint16_t>(*page), static_cast<std::uint16_t>(*id));
}

void read_pid_profile(MapReader& hid, Ctx& c, const config::Config& cfg, HidSettings& s) {
  const Field field = take(hid, "pid", "the PID settings (profile pid)");
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
