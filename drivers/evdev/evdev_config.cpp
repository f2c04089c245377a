#include "drivers/evdev/evdev_config.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "drivers/evdev/evdev_settings.h"
#include "drivers/io/output_thread.h"
#include "kinematics/kinematics.h"

namespace hapticd::drivers::evdev {
namespace {

using config::schema::Diagnostics;
using config::schema::Field;
using config::schema::format_number;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;
using config::schema::read_hex;

// A key given without a value (`--set device.evdev.poll_interval_ms=`) is absent: that is how
// a key of an example file is removed from the command line.
Field take(MapReader& m, const char* key) {
  Field f = m.take(key);
  if (f.present && f.node.IsNull()) f.present = false;
  return f;
}

void text(MapReader& m, const char* key, std::string& out) {
  if (const auto v = config::schema::read_string(m.diag(), take(m, key))) out = *v;
}

void read_select(MapReader& ev, Selector& sel) {
  const Field field = take(ev, "select");
  if (!field.present) ev.missing("select", "which device: name, vendor_id/product_id, path...");
  MapReader m(ev.diag(), field);
  text(m, "name", sel.name);
  if (const auto v = read_hex(m.diag(), take(m, "vendor_id"), 0xFFFF)) {
    sel.vendor_id = static_cast<std::uint16_t>(*v);
  }
  if (const auto v = read_hex(m.diag(), take(m, "product_id"), 0xFFFF)) {
    sel.product_id = static_cast<std::uint16_t>(*v);
  }
  text(m, "phys", sel.phys);
  text(m, "uniq", sel.uniq);
  const Field path = take(m, "path");
  if (const auto v = config::schema::read_string(m.diag(), path)) {
    if (v->rfind("/dev/input/", 0) != 0) {
      m.diag().error(path.key_mark, path.path,
                     "must be an input device node under /dev/input/ (eventN, or a by-id/ or "
                     "by-path/ link to one), got '" +
                         *v + "'");
    } else {
      sel.path = *v;
    }
  }
  m.finish();
  if (field.present && sel.empty() && m.ok()) {
    m.diag().error(field.key_mark, field.path,
                   "selects every input device: give a name, vendor_id and product_id, phys, "
                   "uniq or a path (`hapticd devices` lists the devices with force feedback)");
  }
}

// code (a name such as ABS_X, or the number), scale and its positions.
void read_axis_keys(MapReader& m, AxisSettings& a) {
  const Field code = take(m, "code");
  if (!code.present) m.missing("code", "the axis: ABS_X, ABS_WHEEL, ... or its number");
  if (code.present) {
    const std::string name = code.node.IsScalar() ? code.node.Scalar() : std::string();
    if (const auto c = abs_code(name)) {
      a.code = *c;
    } else if (name.rfind("ABS_", 0) == 0 || name.empty()) {
      m.diag().error(code.key_mark, code.path,
                     "must be an absolute axis (ABS_X, ABS_Y, ABS_Z, ABS_RX, ABS_RY, ABS_RZ, "
                     "ABS_THROTTLE, ABS_RUDDER, ABS_WHEEL, ABS_GAS, ABS_BRAKE, ...) or its number, "
                     "got " +
                         config::schema::describe_value(code.node));
    } else if (const auto v = read_hex(m.diag(), code, kAbsMax)) {
      a.code = static_cast<int>(*v);
    }
  }
  if (const auto s =
          config::schema::read_choice(m.diag(), take(m, "scale"), {"range", "resolution"})) {
    a.scale = *s == 0 ? Scale::kRange : Scale::kResolution;
  }
  if (const auto v = config::schema::read_bool(m.diag(), take(m, "wraps"))) a.wraps = *v;
  const Field min = take(m, "min"), max = take(m, "max");
  const Field rotary = take(m, "rotary"), offset = take(m, "offset");
  if (a.scale == Scale::kRange) {
    if (!min.present) m.missing("min", "the position (m or rad) at the axis' minimum");
    if (!max.present) m.missing("max", "the position (m or rad) at the axis' maximum");
    number(m, min, Range::any(), a.min);
    number(m, max, Range::any(), a.max);
    if (min.present && max.present && a.min == a.max && m.ok()) {
      m.diag().error(max.key_mark, max.path, "min and max must differ");
    } else if (min.present && max.present && !std::isfinite(a.max - a.min) && m.ok()) {
      // Past it every position would be NaN or infinite (axis_position scales by the span).
      m.diag().error(max.key_mark, max.path,
                     "max - min must be a finite number, got " + format_number(a.max) + " - " +
                         format_number(a.min));
    }
    for (const Field* f : {&rotary, &offset}) {
      if (f->present) m.diag().error(f->key_mark, f->path, "only with scale: resolution");
    }
  } else {
    if (const auto v = config::schema::read_bool(m.diag(), rotary)) a.rotary = *v;
    number(m, offset, Range::any(), a.offset);
    for (const Field* f : {&min, &max}) {
      if (f->present) m.diag().error(f->key_mark, f->path, "only with scale: range");
    }
  }
}

// Two axes: joint i pushes toward axes[i].direction_deg, one of the four along the effect's
// axes, and the two perpendicular, so that the effect's x and y are the joints' own forces.
void check_directions(MapReader& ev, const Field& list, const EvdevSettings& s) {
  const bool x0 = std::fmod(s.axis.direction_deg, 180.0) == 90.0;
  const bool x1 = std::fmod(s.second.direction_deg, 180.0) == 90.0;
  if (x0 != x1) return;
  ev.diag().error(list.key_mark, list.path,
                  "both axes push along the effect's " +
                      std::string(x0 ? "x (90, 270)" : "y (0, 180)") +
                      ": one axis' direction_deg must be 90 or 270 (left, right), the other's 0 or "
                      "180 (down, up)");
}

// One entry of device.evdev.axes: the keys of device.evdev.axis and its direction_deg.
void read_axes_entry(MapReader& w, std::size_t i, AxisSettings& a) {
  a.direction_deg = i == 0 ? 270.0 : 0.0;  // right (+x), down (+y): <linux/input.h>
  read_axis_keys(w, a);
  const Field dir = take(w, "direction_deg");
  number(w, dir, Range::interval(0.0, true, 360.0, false), a.direction_deg);
  if (dir.present && std::fmod(a.direction_deg, 90.0) != 0.0) {
    w.diag().error(dir.key_mark, dir.path,
                   "must be 0 (down), 90 (left), 180 (up) or 270 (right): the way a positive "
                   "force on this joint pushes, along one of the effect's axes, got " +
                       format_number(a.direction_deg));
  }
  w.finish();
}

void read_axes(MapReader& ev, const Field& list, EvdevSettings& s) {
  if (!list.node.IsSequence() || list.node.size() == 0 || list.node.size() > 2) {
    const std::string got = list.node.IsSequence() ? std::to_string(list.node.size()) + " entries"
                                                   : config::schema::describe_value(list.node);
    ev.diag().error(list.key_mark, list.path,
                    "must be a list of 1 or 2 axes, joint i being entry i (an effect's direction "
                    "has two axes): [{code: ABS_X, ...}, {code: ABS_Y, ...}], got " +
                        got);
    return;
  }
  s.joints = static_cast<int>(list.node.size());
  for (std::size_t i = 0; i < list.node.size(); ++i) {
    const YAML::Node entry = list.node[i];
    MapReader w(ev.diag(),
                Field{list.path + "[" + std::to_string(i) + "]", entry, entry.Mark(), true});
    read_axes_entry(w, i, i == 0 ? s.axis : s.second);
  }
  if (s.joints == 2 && ev.ok() && s.axis.code == s.second.code) {
    ev.diag().error(list.key_mark, list.path,
                    abs_name(s.axis.code) + " twice: each joint needs an axis of its own");
  }
  if (s.joints == 2) check_directions(ev, list, s);
}

// `axis` (one joint) or `axes` (one entry per joint), never both, as many as device.kinematics
// has joints. True when `axes` gave them: each entry has its direction_deg (a list of one
// entry's is the effect's).
bool read_axis(MapReader& ev, const config::Config& cfg, EvdevSettings& s) {
  const Field one = take(ev, "axis");
  const Field list = take(ev, "axes");
  if (one.present && list.present) {
    ev.diag().error(list.key_mark, list.path,
                    "refuses " + ev.path() +
                        ".axis beside it: axis is the one axis of a device of one joint, axes "
                        "the axes of its joints; give one of them");
    return true;
  }
  if (list.present) {
    read_axes(ev, list, s);
    if (s.joints == 1) s.direction_deg = s.axis.direction_deg;
  } else {
    if (!one.present) ev.missing("axis", "the absolute axis read as the position (or axes)");
    MapReader m(ev.diag(), one);
    read_axis_keys(m, s.axis);
    m.finish();
  }
  const int joints = kinematics::joint_count(cfg.device.kinematics);
  if ((one.present || list.present) && s.joints != joints) {
    const Field& f = list.present ? list : one;
    ev.diag().error(f.key_mark, f.path,
                    std::to_string(s.joints) + " axis(es) read as " + std::to_string(s.joints) +
                        " joint(s), but device.kinematics (" +
                        std::string(kinematics::kind_name(cfg.device.kinematics.kind)) + ") has " +
                        std::to_string(joints) + ": give " + ev.path() +
                        ".axes one entry per joint (joint i is axes[i])");
  }
  return list.present;
}

// ff_driver, the USB polling interval and the kernel's HZ, and what they allow of loop.rate_hz.
void read_ff_driver(MapReader& ev, const config::Config& cfg, EvdevSettings& s) {
  const Field drv = take(ev, "ff_driver");
  if (!drv.present) ev.missing("ff_driver", "uinput, pidff or memless: the kernel's FF driver");
  if (const auto v = config::schema::read_choice(ev.diag(), drv, {"uinput", "pidff", "memless"})) {
    s.ff_driver = static_cast<FfDriver>(*v);
  }
  const Field poll = take(ev, "poll_interval_ms");
  number(ev, poll, Range::interval(0.0, false, 1000.0, true), s.poll_interval_ms);
  const Field hz = take(ev, "kernel_hz");
  if (const auto v = config::schema::read_integer(ev.diag(), hz, IntRange::between(100, 1000))) {
    s.kernel_hz = static_cast<int>(*v);
  }
  if (s.ff_driver == FfDriver::kUinput && poll.present) {
    ev.diag().error(poll.key_mark, poll.path, "not used by ff_driver uinput (no USB link)");
  }
  if (s.ff_driver != FfDriver::kMemless && hz.present) {
    ev.diag().error(hz.key_mark, hz.path, "only with ff_driver: memless (its timer)");
  }
  const double highest = highest_rate_hz(s);
  if (drv.present && highest > 0.0 && cfg.loop.rate_hz > highest * (1.0 + 1e-9)) {
    ev.diag().error(drv.key_mark, drv.path,
                    std::string(to_string(s.ff_driver)) + " passes at most " +
                        format_number(highest) + " updates a second to the device (" +
                        (s.ff_driver == FfDriver::kMemless && highest == s.kernel_hz
                             ? "one per kernel timer tick, kernel_hz"
                             : "one per USB polling interval, poll_interval_ms") +
                        "): loop.rate_hz " + format_number(cfg.loop.rate_hz) +
                        " is above it (docs/drivers/evdev.md)");
  }
}

// The largest force one effect must render: a joint's max_force; with one effect for two axes
// (effect: direction) the length of both together, the effect's level being the vector's.
double largest_force(const config::Config& cfg, const EvdevSettings& s) {
  const double m0 = cfg.device.max_force[0];
  if (s.joints == 1) return m0;
  const double m1 = cfg.device.max_force[1];
  return s.effect == EffectMode::kDirection ? std::hypot(m0, m1) : std::max(m0, m1);
}

void read_force(MapReader& ev, const config::Config& cfg, bool axes, EvdevSettings& s) {
  const Field fs = take(ev, "force_full_scale");
  if (!fs.present) ev.missing("force_full_scale", "the force (N or N m) at level 0x7fff");
  number(ev, fs, Range::greater_than(0.0), s.force_full_scale);
  const double largest = largest_force(cfg, s);
  if (fs.present && s.force_full_scale > 0.0 && s.force_full_scale < largest) {
    ev.diag().error(fs.key_mark, fs.path,
                    "cannot represent " +
                        std::string(s.joints == 1 ? "device.max_force "
                                    : s.effect == EffectMode::kDirection
                                        ? "both joints' device.max_force together (effect: "
                                          "direction, the level is the force vector's length) "
                                        : "each joint's device.max_force ") +
                        format_number(largest) + " N: the level saturates at " +
                        format_number(s.force_full_scale) + " N");
  }
  const Field dir = take(ev, "direction_deg");
  if (dir.present && axes) {
    ev.diag().error(dir.key_mark, dir.path,
                    "one axis' only: with axes each entry has its own direction_deg");
  } else {
    number(ev, dir, Range::interval(0.0, true, 360.0, false), s.direction_deg);
  }
  number(ev, take(ev, "gain"), Range::interval(0.0, false, 1.0, true), s.gain);
  number(ev, take(ev, "autocenter"), Range::interval(0.0, true, 1.0, true), s.autocenter);
}

// One effect with a direction, or one per axis; by default what the kernel's driver renders
// exactly (docs/drivers/evdev.md, "Two axes"): ff-memless turns a direction into whole degrees.
void read_effect(MapReader& ev, EvdevSettings& s) {
  s.effect = s.ff_driver == FfDriver::kMemless ? EffectMode::kPerAxis : EffectMode::kDirection;
  const Field f = take(ev, "effect");
  if (f.present && s.joints == 1) {
    ev.diag().error(f.key_mark, f.path, "only with two axes (axes): one axis has one effect");
    return;
  }
  if (const auto v = config::schema::read_choice(ev.diag(), f, {"direction", "per_axis"})) {
    s.effect = static_cast<EffectMode>(*v);
  }
}

void read_liveness(MapReader& ev, const config::Config& cfg, EvdevSettings& s) {
  const Field live = take(ev, "liveness_ms");
  number(ev, live, Range::interval(0.0, true, 60000.0, true), s.liveness_ms);
  const double min_ms = 2e3 * cfg.loop.sample_period_s();
  if (live.present && s.liveness_ms > 0.0 && s.liveness_ms < min_ms) {
    ev.diag().error(
        live.key_mark, live.path,
        "must be 0 (no bound) or at least two sample periods (" + format_number(min_ms) + " ms)");
  }
}

// What an update of the effect takes the device, and how many late ones in a row fault.
void read_update(MapReader& ev, const config::Config& cfg, EvdevSettings& s) {
  number(ev, take(ev, "update_latency_ms"), Range::interval(0.0, true, 10000.0, true),
         s.update_latency_ms);
  config::schema::integer(ev, take(ev, "late_update_fault"), IntRange::between(1, 10000),
                          s.late_update_fault);
  s.writer_priority = io::output_thread_priority(cfg.loop.rt_priority);
}

}  // namespace

std::shared_ptr<const config::DriverSettings> read_evdev_section(MapReader& ev,
                                                                 const config::Config& cfg) {
  const std::size_t errors_before = ev.diag().messages().size();
  auto s = std::make_shared<EvdevSettings>();
  read_select(ev, s->select);
  const bool axes = read_axis(ev, cfg, *s);
  read_ff_driver(ev, cfg, *s);
  read_effect(ev, *s);
  read_force(ev, cfg, axes, *s);
  read_liveness(ev, cfg, *s);
  read_update(ev, cfg, *s);
  if (ev.diag().messages().size() != errors_before) return nullptr;
  return s;
}

}  // namespace hapticd::drivers::evdev
