#include "drivers/gpio/gpio_settings.h"

#include <climits>
#include <cmath>
#include <set>
#include <stdexcept>
#include <vector>

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

void read_lines(MapReader& parent, GpioSettings& s) {
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

void read_pwm(MapReader& parent, GpioSettings& s) {
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
  if (const auto v = config::schema::read_integer(d, m.take("chip"), IntRange::between(0, 65535))) {
    s.pwm_chip = static_cast<unsigned>(*v);
  }
  if (const auto v =
          config::schema::read_integer(d, m.take("channel"), IntRange::between(0, 65535))) {
    s.pwm_channel = static_cast<unsigned>(*v);
  }
  // 1 ns .. 1 s: the sysfs PWM interface's unit and far beyond any motor PWM.
  if (const auto v = config::schema::read_integer(d, m.take("period_ns"),
                                                  IntRange::between(1, 1'000'000'000))) {
    s.pwm_period_ns = static_cast<std::uint64_t>(*v);
  }
  if (const auto v = config::schema::read_choice(d, m.take("polarity"), {"normal", "inversed"})) {
    s.pwm_inversed = *v == 1;
  }
  m.finish();
}

void read_encoder(MapReader& m, GpioSettings& s) {
  config::schema::Diagnostics& d = m.diag();
  const Field cpu = m.take("counts_per_unit");
  if (const auto v = config::schema::read_number(d, cpu)) {
    if (*v == 0.0) {
      d.error(cpu.key_mark, cpu.path, "must not be 0 (x4 counts per unit; negative flips)");
    } else {
      s.counts_per_unit = *v;
    }
  }
  const IntRange any_count = IntRange::between(LLONG_MIN, LLONG_MAX);
  if (const auto v = config::schema::read_integer(d, m.take("start_count"), any_count)) {
    s.start_count = *v;
  }
  if (const auto v = config::schema::read_integer(d, m.take("index_count"), any_count)) {
    s.index_count = *v;
  }
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

}  // namespace

std::shared_ptr<const config::DriverSettings> read_gpio_section(MapReader& m,
                                                                const config::Config& cfg) {
  auto s = std::make_shared<GpioSettings>();
  config::schema::Diagnostics& d = m.diag();
  const std::size_t errors_before = d.messages().size();
  if (const auto v = config::schema::read_string(d, m.take("chip"))) {
    const Field f = m.take("chip");
    if (v->empty()) {
      d.error(f.key_mark, f.path, "must name a GPIO chip (path, gpiochipN or label)");
    } else {
      s->chip = *v;
    }
  }
  read_lines(m, *s);
  if (const auto v = config::schema::read_bool(d, m.take("encoder_active_low"))) {
    s->encoder_active_low = *v;
  }
  if (const auto v = config::schema::read_bool(d, m.take("fault_active_low"))) {
    s->fault_active_low = *v;
  }
  if (const auto v =
          config::schema::read_choice(d, m.take("direction_positive"), {"high", "low"})) {
    s->direction_positive_high = *v == 0;
  }
  read_encoder(m, *s);
  read_pwm(m, *s);
  if (const Field f = m.take("on_disable"); f.present) {
    d.error(f.key_mark, f.path,
            "is no longer a setting: hapticd stops the motor with duty 0 on the enabled PWM "
            "channel, the only stop Linux's PWM API defines (a disabled channel's output is "
            "undefined); whether the motor then brakes or coasts is the motor driver's decay "
            "mode, in its data sheet (docs/drivers/gpio.md). Remove the key");
  }
  if (!s->line_index && m.take("index_count").present) {
    const Field f = m.take("index_count");
    d.error(f.key_mark, f.path, "needs lines.index (there is no index line to re-zero on)");
  }
  (void)cfg;  // nothing here depends on loop.* or device.*: the delay is computed later
  if (d.messages().size() != errors_before) return nullptr;
  return s;
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
