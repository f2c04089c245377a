#include "drivers/evdev/evdev_settings.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

namespace hapticd::drivers::evdev {
namespace {

struct Named {
  std::string_view name;
  int code;
};

// linux/input-event-codes.h's single absolute axes (the multi-touch ones are per contact).
constexpr std::array<Named, 27> kAbsNames{{
    {"ABS_X", 0x00},        {"ABS_Y", 0x01},       {"ABS_Z", 0x02},        {"ABS_RX", 0x03},
    {"ABS_RY", 0x04},       {"ABS_RZ", 0x05},      {"ABS_THROTTLE", 0x06}, {"ABS_RUDDER", 0x07},
    {"ABS_WHEEL", 0x08},    {"ABS_GAS", 0x09},     {"ABS_BRAKE", 0x0a},    {"ABS_HAT0X", 0x10},
    {"ABS_HAT0Y", 0x11},    {"ABS_HAT1X", 0x12},   {"ABS_HAT1Y", 0x13},    {"ABS_HAT2X", 0x14},
    {"ABS_HAT2Y", 0x15},    {"ABS_HAT3X", 0x16},   {"ABS_HAT3Y", 0x17},    {"ABS_PRESSURE", 0x18},
    {"ABS_DISTANCE", 0x19}, {"ABS_TILT_X", 0x1a},  {"ABS_TILT_Y", 0x1b},   {"ABS_TOOL_WIDTH", 0x1c},
    {"ABS_VOLUME", 0x20},   {"ABS_PROFILE", 0x21}, {"ABS_MISC", 0x28},
}};

}  // namespace

const char* to_string(FfDriver d) noexcept {
  switch (d) {
    case FfDriver::kUinput:
      return "uinput";
    case FfDriver::kPidff:
      return "pidff";
    case FfDriver::kMemless:
      return "memless";
  }
  return "?";
}

const char* to_string(EffectMode m) noexcept {
  return m == EffectMode::kDirection ? "direction" : "per_axis";
}

std::uint16_t direction_of(double degrees) noexcept {
  const double turns = std::fmod(degrees, 360.0) / 360.0;
  return static_cast<std::uint16_t>(std::lround(turns * 65536.0) & 0xFFFF);
}

std::optional<int> abs_code(std::string_view name) noexcept {
  for (const Named& n : kAbsNames) {
    if (n.name == name) return n.code;
  }
  return std::nullopt;
}

std::string abs_name(int code) {
  for (const Named& n : kAbsNames) {
    if (n.code == code) return std::string(n.name);
  }
  char text[16];
  std::snprintf(text, sizeof text, "ABS_0x%02x", static_cast<unsigned>(code) & 0xFFu);
  return text;
}

double axis_position(std::int64_t value, const AxisSettings& axis,
                     const AxisRange& range) noexcept {
  if (axis.scale == Scale::kResolution) {
    const double per_unit = axis.rotary ? range.resolution : range.resolution * 1e3;
    return value / per_unit + axis.offset;
  }
  const double span = static_cast<double>(range.maximum) - range.minimum;
  return axis.min + (static_cast<double>(value) - range.minimum) / span * (axis.max - axis.min);
}

int counter_bits(const AxisRange& range) noexcept {
  const std::int64_t values = std::int64_t{range.maximum} - range.minimum + 1;
  for (int n = 1; n <= 32; ++n) {
    if (values == std::int64_t{1} << n) return n;
  }
  return 0;
}

std::int16_t force_level(double force, double full_scale) noexcept {
  if (!std::isfinite(force)) return 0;
  const double level = std::round(force / full_scale * kLevelMax);
  return static_cast<std::int16_t>(std::clamp(level, -double{kLevelMax}, double{kLevelMax}));
}

double level_force(int level, double full_scale) noexcept {
  return static_cast<double>(level) * (full_scale / kLevelMax);
}

PlaneVector direction_vector(std::uint16_t direction) noexcept {
  // The four the axes lie along exactly: sin and cos of pi are not 0 in double.
  switch (direction) {
    case 0x0000:
      return {0.0, 1.0};
    case 0x4000:
      return {-1.0, 0.0};
    case 0x8000:
      return {0.0, -1.0};
    case 0xC000:
      return {1.0, 0.0};
    default:
      break;
  }
  const double a = direction / 65536.0 * 2.0 * std::numbers::pi;
  return {-std::sin(a), std::cos(a)};
}

DirectedLevel directed_level(double force0, double force1, const EvdevSettings& s,
                             std::uint16_t previous) noexcept {
  const PlaneVector a0 = direction_vector(direction_of(s.axis.direction_deg));
  const PlaneVector a1 = direction_vector(direction_of(s.second.direction_deg));
  if (!std::isfinite(force0) || !std::isfinite(force1)) return {previous, 0};
  const double x = force0 * a0.x + force1 * a1.x;
  const double y = force0 * a0.y + force1 * a1.y;
  const std::int16_t level = force_level(std::hypot(x, y), s.force_full_scale);
  if (level == 0) return {previous, 0};
  // (-sin t, cos t) = (x, y) / |(x, y)|: t = atan2(-x, y), in turns of 65536.
  const double turns = std::atan2(-x, y) / (2.0 * std::numbers::pi);
  const auto direction = static_cast<std::uint16_t>(std::lround(turns * 65536.0) & 0xFFFF);
  return {direction, level};
}

double plane_force(int joint, std::uint16_t direction, int level, const EvdevSettings& s) noexcept {
  const PlaneVector v = direction_vector(direction);
  const PlaneVector a = direction_vector(direction_of(s.axis_of(joint).direction_deg));
  const double along = a.x != 0.0 ? v.x : v.y;  // the device's own +x or +y
  return level_force(level, s.force_full_scale) * along;
}

namespace {

// Whole samples of delay for `seconds` from a write to its answer: the answer is read at the
// tick ceil(seconds / T) after the write's, one tick later than an in-process device gives it.
int samples_for(double seconds, double sample_period_s) noexcept {
  // A hair of tolerance, so 2 ms over 1 ms is 2 periods, not 3.
  const int periods = static_cast<int>(std::ceil(seconds / sample_period_s - 1e-9));
  return std::max(0, periods - 1);
}

}  // namespace

int declared_delay_samples(const EvdevSettings& s, double sample_period_s) noexcept {
  const int update = samples_for(2.0 * s.update_latency_ms * 1e-3, sample_period_s);
  if (s.ff_driver == FfDriver::kUinput) return update;
  double seconds = 2.0 * s.poll_interval_ms * 1e-3;
  if (s.ff_driver == FfDriver::kMemless) seconds += 1.0 / s.kernel_hz;
  return samples_for(seconds, sample_period_s) + update;
}

double covered_update_s(const EvdevSettings& s, double sample_period_s) noexcept {
  const int update = samples_for(2.0 * s.update_latency_ms * 1e-3, sample_period_s);
  return (update + 1) * sample_period_s / 2.0;
}

double highest_rate_hz(const EvdevSettings& s) noexcept {
  switch (s.ff_driver) {
    case FfDriver::kUinput:
      return 0.0;
    case FfDriver::kPidff:
      return 1e3 / s.poll_interval_ms;
    case FfDriver::kMemless:
      return std::min(1e3 / s.poll_interval_ms, static_cast<double>(s.kernel_hz));
  }
  return 0.0;
}

}  // namespace hapticd::drivers::evdev

namespace hapticd::drivers::evdev {
const EvdevSettings& evdev_settings(const DriverContext& ctx) {
  const auto* s = dynamic_cast<const EvdevSettings*>(ctx.settings.get());
  if (s == nullptr) throw std::logic_error("device.driver is not evdev: no device.evdev settings");
  return *s;
}
}  // namespace hapticd::drivers::evdev
