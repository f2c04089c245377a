#include "drivers/gpio/gpio_settings.h"

#include <climits>
#include <cmath>
#include <set>
#include <stdexcept>
#include <vector>

#include "base/joints.h"
#include "kinematics/kinematics.h"

namespace hapticd::drivers::gpio {
namespace {

using config::schema::Field;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::Range;

constexpr long long kMaxLine = 4095;  // far above any gpiochip's line count

std::optional<unsigned> line(MapReader& m, std::string_view key) {
  const auto v =
      config::schema::read_integer(m.diag(), m.take(key), IntRange::between(0, kMaxLine));
  if (!v) return std::nullopt;
  return static_cast<unsigned>(*v);
}

void read_lines(MapReader& parent, GpioJointSettings& s) {
  const Field field = parent.take("lines");
  MapReader m(parent.diag(), field);
  if (!field.present) m.missing("lines", "the encoder's A and B lines and the direction line");
  struct Named {
    const char* key;
    std::optional<unsigned> value;
    bool required;
  };
  std::vector<Named> lines = {{"a", line(m, "a"), true},
                              {"b", line(m, "b"), true},
                              {"index", line(m, "index"), false},
                              {"direction", line(m, "direction"), true},
                              {"fault", line(m, "fault"), false}};
  std::set<unsigned> seen;
  for (const Named& n : lines) {
    const Field f = m.take(n.key);  // already taken: look-up only, for the place
    if (n.required && !f.present && field.present) m.missing(n.key, "a line offset on the chip");
    if (n.value && !seen.insert(*n.value).second) {
      m.diag().error(f.key_mark, f.path, "line " + std::to_string(*n.value) + " is used twice");
    }
  }
  if (lines[0].value) s.line_a = *lines[0].value;
  if (lines[1].value) s.line_b = *lines[1].value;
  s.line_index = lines[2].value;
  if (lines[3].value) s.line_direction = *lines[3].value;
  s.line_fault = lines[4].value;
  m.finish();
}

std::optional<unsigned> pwm_number(MapReader& m, std::string_view key) {
  const auto v = config::schema::read_integer(m.diag(), m.take(key), IntRange::between(0, 65535));
  if (!v) return std::nullopt;
  return static_cast<unsigned>(*v);
}

// device.gpio.pwm: what every joint's channel shares, the chip every joint takes unless it names
// its own, and (one joint) the channel. Returns the channel's field, for the list's refusal.
Field read_pwm(MapReader& parent, GpioSettings& s, GpioJointSettings& base) {
  const Field field = parent.take("pwm");
  MapReader m(parent.diag(), field);
  config::schema::Diagnostics& d = m.diag();
  if (const auto v = config::schema::read_string(d, m.take("sysfs_root"))) {
    const Field f = m.take("sysfs_root");
    if (v->empty() || v->front() != '/') {
      d.error(f.key_mark, f.path, "must be an absolute path, got '" + *v + "'");
    } else {
      s.pwm_sysfs_root = *v;
    }
  }
  if (const auto v = pwm_number(m, "chip")) base.pwm_chip = *v;
  if (const auto v = pwm_number(m, "channel")) base.pwm_channel = *v;
  // 1 ns .. 1 s: the sysfs PWM interface's unit and far beyond any motor PWM.
  if (const auto v = config::schema::read_integer(d, m.take("period_ns"),
                                                  IntRange::between(1, 1'000'000'000))) {
    s.pwm_period_ns = static_cast<std::uint64_t>(*v);
  }
  if (const auto v = config::schema::read_choice(d, m.take("polarity"), {"normal", "inversed"})) {
    s.pwm_inversed = *v == 1;
  }
  const Field channel = m.take("channel");
  m.finish();
  return channel;
}

// chip, direction_positive, counts_per_unit: a joint's own, or the section's for every joint.
void read_joint_shared(MapReader& m, GpioJointSettings& j) {
  config::schema::Diagnostics& d = m.diag();
  if (const auto v = config::schema::read_string(d, m.take("chip"))) {
    const Field f = m.take("chip");
    if (v->empty()) {
      d.error(f.key_mark, f.path, "must name a GPIO chip (path, gpiochipN or label)");
    } else {
      j.chip = *v;
    }
  }
  if (const auto v =
          config::schema::read_choice(d, m.take("direction_positive"), {"high", "low"})) {
    j.direction_positive_high = *v == 0;
  }
  const Field cpu = m.take("counts_per_unit");
  if (const auto v = config::schema::read_number(d, cpu)) {
    if (*v == 0.0) {
      d.error(cpu.key_mark, cpu.path, "must not be 0 (x4 counts per unit; negative flips)");
    } else {
      j.counts_per_unit = *v;
    }
  }
}

// lines, start_count, index_count: each joint's own.
void read_joint_own(MapReader& m, GpioJointSettings& j) {
  config::schema::Diagnostics& d = m.diag();
  read_lines(m, j);
  const IntRange any_count = IntRange::between(LLONG_MIN, LLONG_MAX);
  if (const auto v = config::schema::read_integer(d, m.take("start_count"), any_count)) {
    j.start_count = *v;
  }
  if (const auto v = config::schema::read_integer(d, m.take("index_count"), any_count)) {
    j.index_count = *v;
  }
  if (!j.line_index && m.take("index_count").present) {
    const Field f = m.take("index_count");
    d.error(f.key_mark, f.path, "needs lines.index (there is no index line to re-zero on)");
  }
}

void read_tolerances(MapReader& m, GpioSettings& s) {
  config::schema::Diagnostics& d = m.diag();
  if (const auto v =
          config::schema::read_number(d, m.take("max_edge_rate"), Range::at_least(0.0))) {
    s.max_edge_rate_hz = *v;
  }
  if (const auto v = config::schema::read_integer(d, m.take("missed_edge_fault"),
                                                  IntRange::between(0, kMaxMissedEdgeFault))) {
    s.missed_edge_fault = static_cast<std::uint64_t>(*v);
  }
  if (const auto v = config::schema::read_number(d, m.take("missed_edge_window"),
                                                 Range::interval(0.0, false, 3600.0, true))) {
    s.missed_edge_window_s = *v;
  }
}

// The kernel's name of a chip as given ("/dev/gpiochip1" and "gpiochip1" are one chip; a
// label is compared as written: two spellings of one chip are the kernel's to refuse, EBUSY).
std::string chip_key(const std::string& chip) {
  return chip.rfind("/dev/", 0) == 0 ? chip.substr(5) : chip;
}

// Each line of a joint with the key that names it, for the messages about a line used twice.
std::vector<std::pair<std::string, unsigned>> named_lines(const GpioJointSettings& j) {
  std::vector<std::pair<std::string, unsigned>> out = {
      {"lines.a", j.line_a}, {"lines.b", j.line_b}, {"lines.direction", j.line_direction}};
  if (j.line_index) out.emplace_back("lines.index", *j.line_index);
  if (j.line_fault) out.emplace_back("lines.fault", *j.line_fault);
  return out;
}

// Joint `i` (just read, at `f`) against the joints before it: no line of a chip and no PWM
// channel driven twice.
void check_distinct(MapReader& m, const Field& f, const std::string& list,
                    const std::vector<GpioJointSettings>& joints, std::size_t i,
                    const std::string& sysfs_root) {
  const GpioJointSettings& now = joints[i];
  const std::string at = list + "[" + std::to_string(i) + "]";
  for (std::size_t k = 0; k < i; ++k) {
    const GpioJointSettings& was = joints[k];
    const std::string before = list + "[" + std::to_string(k) + "]";
    if (chip_key(was.chip) == chip_key(now.chip)) {
      for (const auto& [key, line] : named_lines(now)) {
        for (const auto& [old_key, old_line] : named_lines(was)) {
          if (line != old_line) continue;
          m.diag().error(f.key_mark, at + "." + key,
                         "line " + std::to_string(line) + " of " + now.chip + " twice: " + before +
                             "." + old_key + " and " + at + "." + key +
                             " (each joint needs its own lines)");
        }
      }
    }
    if (was.pwm_chip == now.pwm_chip && was.pwm_channel == now.pwm_channel) {
      m.diag().error(f.key_mark, at + ".pwm",
                     sysfs_root + "/pwmchip" + std::to_string(now.pwm_chip) + "/pwm" +
                         std::to_string(now.pwm_channel) + " twice: " + before + ".pwm and " + at +
                         ".pwm (each joint needs its own PWM channel)");
    }
  }
}

// One entry of device.gpio.joints, the section's chip, direction and resolution its defaults.
GpioJointSettings read_joint_entry(MapReader& w, const GpioJointSettings& base) {
  GpioJointSettings j = base;
  read_joint_shared(w, j);
  read_joint_own(w, j);
  const Field pwm_field = w.take("pwm");
  MapReader pwm(w.diag(), pwm_field);
  if (!pwm_field.present) w.missing("pwm", "the joint's PWM channel: {channel: N}");
  if (const auto v = pwm_number(pwm, "chip")) j.pwm_chip = *v;
  const Field channel = pwm.take("channel");
  if (pwm_field.present && !channel.present) pwm.missing("channel", "each joint drives its own");
  if (const auto v = pwm_number(pwm, "channel")) j.pwm_channel = *v;
  pwm.finish();
  w.finish();
  return j;
}

// device.gpio.joints: 1..kMaxJoints entries, joint i is entry i.
void read_joint_list(MapReader& m, const Field& f, const GpioJointSettings& base, GpioSettings& s) {
  config::schema::Diagnostics& d = m.diag();
  if (!f.node.IsSequence() || f.node.size() == 0 || f.node.size() > base::kMaxJoints) {
    const std::string got = f.node.IsSequence() ? std::to_string(f.node.size()) + " entries"
                                                : config::schema::describe_value(f.node);
    d.error(f.key_mark, f.path,
            "must be a list of 1 to " + std::to_string(base::kMaxJoints) +
                " joints, joint i being entry i: [{lines: {a: 0, b: 1, direction: 2}, pwm: "
                "{channel: 0}}, ...], got " +
                got);
    return;
  }
  s.joints.clear();
  s.listed = true;
  for (std::size_t i = 0; i < f.node.size(); ++i) {
    const YAML::Node entry = f.node[i];
    const Field at{f.path + "[" + std::to_string(i) + "]", entry, entry.Mark(), true};
    MapReader w(d, at);
    if (!w.ok()) continue;
    s.joints.push_back(read_joint_entry(w, base));
    check_distinct(m, at, f.path, s.joints, s.joints.size() - 1, s.pwm_sysfs_root);
  }
}

// With device.gpio.joints, the keys that belong to one joint stay out of the section: which
// joint would they be?
void refuse_one_joint_keys(MapReader& m, const Field& list, const Field& pwm_channel) {
  for (const char* key : {"lines", "start_count", "index_count"}) {
    const Field f = m.take(key);
    if (!f.present || f.node.IsNull()) continue;
    m.diag().error(f.key_mark, f.path,
                   "is the one joint's of a device of one joint, beside " + list.path +
                       ", which gives each joint its own: move it into the joints' entries");
  }
  if (pwm_channel.present && !pwm_channel.node.IsNull()) {
    m.diag().error(pwm_channel.key_mark, pwm_channel.path,
                   "is the one joint's channel of a device of one joint, beside " + list.path +
                       ", which gives each joint its own: give each entry pwm.channel");
  }
}

// The joints the section drives against the mechanism's (the run refuses the device otherwise).
void check_joint_count(MapReader& m, const GpioSettings& s, const config::Config& cfg) {
  const auto joints = static_cast<std::size_t>(kinematics::joint_count(cfg.device.kinematics));
  if (s.joints.size() == joints) return;
  const std::string n = std::to_string(s.joints.size());
  m.diag().error(m.mark(), m.path(),
                 n + " joint(s) of encoder and PWM, but device.kinematics (" +
                     std::string(kinematics::kind_name(cfg.device.kinematics.kind)) + ") has " +
                     std::to_string(joints) + ": give " + m.path() +
                     ".joints one entry per joint (joint i is joints[i])");
}

}  // namespace

std::shared_ptr<const config::DriverSettings> read_gpio_section(MapReader& m,
                                                                const config::Config& cfg) {
  auto s = std::make_shared<GpioSettings>();
  config::schema::Diagnostics& d = m.diag();
  const std::size_t errors_before = d.messages().size();
  GpioJointSettings base;  // the one joint, or every listed joint's defaults
  read_joint_shared(m, base);
  if (const auto v = config::schema::read_bool(d, m.take("encoder_active_low"))) {
    s->encoder_active_low = *v;
  }
  if (const auto v = config::schema::read_bool(d, m.take("fault_active_low"))) {
    s->fault_active_low = *v;
  }
  read_tolerances(m, *s);
  const Field pwm_channel = read_pwm(m, *s, base);
  const Field list = m.take("joints");
  if (list.present && !list.node.IsNull()) {
    refuse_one_joint_keys(m, list, pwm_channel);
    read_joint_list(m, list, base, *s);
  } else {
    read_joint_own(m, base);
    s->joints = {base};
  }
  if (const Field f = m.take("on_disable"); f.present) {
    d.error(f.key_mark, f.path,
            "is no longer a setting: hapticd stops the motor with duty 0 on the enabled PWM "
            "channel, the only stop Linux's PWM API defines (a disabled channel's output is "
            "undefined); whether the motor then brakes or coasts is the motor driver's decay "
            "mode, in its data sheet (docs/drivers/gpio.md). Remove the key");
  }
  if (d.messages().size() != errors_before) return nullptr;
  check_joint_count(m, *s, cfg);
  if (d.messages().size() != errors_before) return nullptr;
  return s;
}

std::string GpioSettings::key(std::size_t i, const std::string& k) const {
  return listed ? "device.gpio.joints[" + std::to_string(i) + "]." + k : "device.gpio." + k;
}

std::string GpioSettings::joint_name(std::size_t i) const {
  if (!listed) return "";
  const GpioJointSettings& j = joints.at(i);
  return "joint " + std::to_string(i) + " (" + j.chip + " lines " + std::to_string(j.line_a) + "," +
         std::to_string(j.line_b) + ", pwmchip" + std::to_string(j.pwm_chip) + "/pwm" +
         std::to_string(j.pwm_channel) + ")";
}

const GpioSettings& gpio_settings(const DriverContext& ctx) {
  const auto* s = dynamic_cast<const GpioSettings*>(ctx.settings.get());
  if (s == nullptr) throw std::logic_error("device.driver is not gpio: no device.gpio settings");
  return *s;
}

int declared_delay_samples(const GpioSettings& s, double sample_period_s) {
  const double periods = static_cast<double>(s.pwm_period_ns) * 1e-9 / sample_period_s;
  // A hair of tolerance: a period of exactly T must not become 1 by rounding.
  const double whole = std::ceil(periods - 1e-9);
  return whole <= 1.0 ? 0 : static_cast<int>(whole) - 1;
}

}  // namespace hapticd::drivers::gpio
