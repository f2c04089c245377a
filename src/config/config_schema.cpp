// The schema of a hapticd configuration, section by section. Each reader takes the keys it
// knows, checks them, fills Config, and leaves the rest for MapReader::finish to report.
#include "config/config_schema.h"

#include <algorithm>
#include <climits>
#include <utility>

namespace hapticd::config::schema {
namespace {

const Options<ClockMode> kClocks{{"realtime", ClockMode::kRealtime},
                                 {"freerun", ClockMode::kFreerun}};
const Options<Discretization> kDiscretizations{{"backward", Discretization::kBackward},
                                               {"tustin", Discretization::kTustin}};

struct LoopResult {
  std::optional<double> rate_hz;  // empty when rate_hz is invalid
};

LoopResult read_loop(MapReader& top, LoopConfig& loop) {
  MapReader m(top.diag(), top.take("loop"));
  LoopResult result;
  const Field rate = m.take("rate_hz");
  // Below 1 Hz nothing is haptic, and T = 1/rate_hz must stay a finite, ordinary number.
  const auto r = read_number(m.diag(), rate, Range::interval(1.0, true, 100000.0, true));
  if (r) loop.rate_hz = *r;
  if (r || !rate.present) result.rate_hz = loop.rate_hz;
  if (const auto v = choice(m.diag(), m.take("clock"), kClocks)) loop.clock = *v;
  integer(m, "rt_priority", IntRange::between(1, 99), loop.rt_priority);
  integer(m, "cpu", IntRange::at_least(-1, INT_MAX), loop.cpu);
  integer(m, "overrun_fault_streak", IntRange::at_least(1, INT_MAX), loop.overrun_fault_streak);
  m.finish();
  return result;
}

// device.driver selects one schema; its section device.<driver> is read by the driver's own
// code, and the sections of the other drivers are refused rather than ignored.
void read_driver_section(MapReader& m, const DriverSchemas& drivers, bool driver_ok, Config& cfg) {
  const DriverSchema* selected = nullptr;
  for (const DriverSchema& s : drivers) {
    if (!s.read_section) continue;
    if (driver_ok && s.name == cfg.device.driver) {
      selected = &s;
    } else if (driver_ok) {
      m.not_used(s.name, "device.driver '" + cfg.device.driver + "'");
    } else {
      m.take(s.name);  // the driver is wrong: which section applies is unknown
    }
  }
  if (selected == nullptr) return;
  MapReader section(m.diag(), m.take(selected->name));
  if (!section.ok()) return;
  cfg.device.settings = selected->read_section(section, cfg);
  section.finish();
}

// device.mass, damping, max_force: one number for every joint, or a list of one per joint of
// device.kinematics (read before: `joints`). Each value in `range`.
void joint_values(MapReader& m, const Field& field, const Range& range, std::size_t joints,
                  JointValues& out) {
  if (!field.present) return;
  if (!field.node.IsSequence()) {
    if (const auto v = read_number(m.diag(), field, range)) out = JointValues(*v);
    return;
  }
  if (field.node.size() != joints) {
    m.diag().error(field.key_mark, field.path,
                   "must be one number (every joint's) or a list of one per joint: "
                   "device.kinematics has " +
                       std::to_string(joints) + (joints == 1 ? " joint" : " joints") + ", got " +
                       std::to_string(field.node.size()) + " numbers");
    return;
  }
  const auto list = read_number_list(m.diag(), field, range);
  for (std::size_t i = 0; list && i < joints; ++i) out[i] = (*list)[i];
}

void read_device(MapReader& top, std::optional<double> rate_hz, const std::string& base_dir,
                 const DriverSchemas& drivers, Config& cfg) {
  MapReader m(top.diag(), top.take("device"));
  Diagnostics& d = m.diag();
  std::vector<std::string> names;
  for (const DriverSchema& s : drivers) names.push_back(s.name);
  const Field driver = m.take("driver");
  const auto index = read_choice(d, driver, names);
  if (index) cfg.device.driver = names[*index];
  const Field mass = m.take("mass"), damping = m.take("damping"), max_force = m.take("max_force");
  read_kinematics(m, cfg.device.kinematics);
  const auto joints = static_cast<std::size_t>(kinematics::joint_count(cfg.device.kinematics));
  joint_values(m, mass, Range::greater_than(0.0), joints, cfg.device.mass);
  joint_values(m, damping, Range::greater_than(0.0), joints, cfg.device.damping);
  joint_values(m, max_force, Range::greater_than(0.0), joints, cfg.device.max_force);
  read_plant(m, rate_hz, base_dir, cfg.device.kinematics, cfg.device.sim);
  read_driver_section(m, drivers, index.has_value() || !driver.present, cfg);
  m.finish();
}

// A rational filter {numerator, denominator} in powers of z^-1. Both lists are needed; the
// denominator's leading coefficient is what the filter is normalised by.
std::optional<std::pair<Coefficients, Coefficients>> read_rational(MapReader& parent,
                                                                   std::string_view key,
                                                                   const std::string& filter,
                                                                   bool is_coupling) {
  const Field field = parent.take(key);
  // A key with everything below it commented out means "not configured".
  if (!field.present || field.node.IsNull()) return std::nullopt;
  MapReader m(parent.diag(), field);
  if (!m.ok()) return std::nullopt;
  Diagnostics& d = m.diag();
  const Field num_field = m.take("numerator");
  const Field den_field = m.take("denominator");
  if (!num_field.present) d.error(field.key_mark, field.path, "missing 'numerator'");
  if (!den_field.present) d.error(field.key_mark, field.path, "missing 'denominator'");
  const auto num = read_number_list(d, num_field);
  const auto den = read_number_list(d, den_field);
  m.finish();
  if (den && den->front() == 0.0) {
    d.error(den_field.key_mark, den_field.path,
            "leading coefficient must be non-zero (it normalises " + filter + "), got '" +
                den_field.node[0].Scalar() + "'");
    return std::nullopt;
  }
  if (!num || !den) return std::nullopt;
  if (is_coupling) {
    // The controller's filter histories are fixed-size (preallocated for the RT thread).
    for (const auto& [list, f] : {std::pair{&*num, &num_field}, std::pair{&*den, &den_field}}) {
      if (list->size() > kMaxCouplingCoefficients) {
        d.error(f->key_mark, f->path,
                "at most " + std::to_string(kMaxCouplingCoefficients) + " coefficients, got " +
                    std::to_string(list->size()));
        return std::nullopt;
      }
    }
    // The contact law solves the algebraic loop f = E(q - c0 f) in closed form; that solution
    // is unique only for e0 c0 >= 0, and e0 >= 0 always (K, B >= 0), so c0 must be too.
    const double c0 = num->front() / den->front();
    if (c0 < 0.0) {
      d.error(num_field.key_mark, num_field.path,
              "direct feed-through numerator[0]/denominator[0] must be >= 0 for the contact "
              "algebraic loop to have a unique solution, got " +
                  format_number(c0));
      return std::nullopt;
    }
  }
  return std::make_pair(*num, *den);
}

void read_wall(MapReader& top, WallConfig& wall) {
  MapReader m(top.diag(), top.take("wall"));
  Diagnostics& d = m.diag();
  number(m, "position", Range::any(), wall.position);
  const Field normal = m.take("normal");
  if (normal.present) {
    double v = 0.0;
    if (normal.node.IsScalar() && parse_finite(normal.node.Scalar(), v) &&
        (v == 1.0 || v == -1.0)) {
      wall.normal = v > 0.0 ? 1 : -1;
    } else {
      d.error(normal.key_mark, normal.path, "must be +1 or -1, got " + describe_value(normal.node));
    }
  }
  read_wall_law(m, wall);
  m.finish();
}

void read_analysis(MapReader& top, AnalysisConfig& analysis) {
  MapReader m(top.diag(), top.take("analysis"));
  MapReader op(m.diag(), m.take("operator"));
  number(op, "stiffness", Range::greater_than(0.0), analysis.operator_stiffness);
  number(op, "damping", Range::at_least(0.0), analysis.operator_damping);
  op.finish();
  if (auto w = read_rational(m, "transparency_weight", "W(z)", false)) {
    analysis.transparency_weight_numerator = std::move(w->first);
    analysis.transparency_weight_denominator = std::move(w->second);
  }
  m.finish();
}

void read_telemetry(MapReader& top, TelemetryConfig& telemetry) {
  MapReader m(top.diag(), top.take("telemetry"));
  if (const auto v = read_string(m.diag(), m.take("log"))) telemetry.log_path = *v;
  // The ring is allocated, prefaulted and locked in memory: 2^22 records are 300 MB.
  if (const auto v = read_integer(m.diag(), m.take("ring_capacity"),
                                  IntRange::between(64, kMaxRingCapacity))) {
    telemetry.ring_capacity = static_cast<std::uint32_t>(*v);
  }
  const Field segment = m.take("max_segment_mb");
  if (const auto v = read_integer(m.diag(), segment, IntRange::between(0, kMaxLogMegabytes))) {
    telemetry.max_segment_mb = static_cast<std::uint32_t>(*v);
  }
  const Field total = m.take("max_total_mb");
  if (const auto v = read_integer(m.diag(), total, IntRange::between(0, kMaxLogMegabytes))) {
    telemetry.max_total_mb = static_cast<std::uint32_t>(*v);
  }
  // The segment being written is never deleted: without a segment size nothing bounds it, and
  // a cap below two segments would delete each one as soon as the next begins. Said at the key
  // that is off (a segment size of 0, a cap too small) when the document has it.
  const std::uint64_t cap = telemetry.max_total_mb, seg = telemetry.max_segment_mb;
  if (cap > 0 && seg == 0) {
    const Field& at = segment.present ? segment : total;
    m.diag().error(at.key_mark, at.path,
                   "max_segment_mb 0 with max_total_mb " + std::to_string(cap) +
                       ": one endless segment could not be kept under the cap (make "
                       "max_total_mb 0 too, or give a segment size)");
  } else if (cap > 0 && cap < 2 * seg) {
    const Field& at = total.present ? total : segment;
    m.diag().error(at.key_mark, at.path,
                   "max_total_mb " + std::to_string(cap) + " is less than twice max_segment_mb " +
                       std::to_string(seg) +
                       ": the cap must hold the segment being written and the one before it");
  }
  m.finish();
}

}  // namespace

void read_wall_law(MapReader& m, WallConfig& wall) {
  Diagnostics& d = m.diag();
  number(m, "stiffness", Range::at_least(0.0), wall.stiffness);
  number(m, "damping", Range::at_least(0.0), wall.damping);
  if (const auto v = choice(d, m.take("discretization"), kDiscretizations)) {
    wall.discretization = *v;
  }
  // Beyond 100 samples no useful wall is passive (b_req grows like K T d), and the analysis
  // of the delayed loop must stay well under a second.
  integer(m, "delay_samples", IntRange::between(0, kMaxDelaySamples), wall.delay_samples);
  if (const auto v = read_bool(d, m.take("no_pull"))) wall.no_pull = *v;
  if (auto c = read_rational(m, "coupling", "C(z)", true)) {
    wall.coupling = {true, std::move(c->first), std::move(c->second)};
  }
}

void read_config(Diagnostics& diag, const YAML::Node& root, const std::string& base_dir,
                 const DriverSchemas& drivers, Config& config) {
  MapReader top(diag, {"", root, root.Mark(), true});
  const LoopResult loop = read_loop(top, config.loop);
  read_device(top, loop.rate_hz, base_dir, drivers, config);
  // One joint has its `wall`; several task axes have `walls`, and each refuses the other.
  const int task_axes = kinematics::joint_count(config.device.kinematics);
  const std::string kind = kinematics::kind_name(config.device.kinematics.kind);
  if (task_axes == 1) {
    top.not_used("walls", "a device of one joint (its wall is `wall`)");
    read_wall(top, config.wall);
  } else {
    top.not_used("wall", "device.kinematics kind " + kind + " (its walls are `walls`)");
    read_walls(top, task_axes, config.walls);
  }
  read_safety(top, config.safety);
  read_analysis(top, config.analysis);
  read_telemetry(top, config.telemetry);
  top.finish();
}

}  // namespace hapticd::config::schema
