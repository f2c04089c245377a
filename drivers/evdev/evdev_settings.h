// The evdev driver's settings, the section device.evdev (read and validated by
// evdev_config.cpp; every key is documented in config/evdev.yaml), and the arithmetic both the
// driver and its simulated device do with them: the axis mapped to SI, the force as an
// FF_CONSTANT level, and the delay each class of kernel force-feedback driver adds
// (docs/drivers/evdev.md). Plain values; no OS header (the kernel's numbers are restated here
// and checked against <linux/input.h> where the driver includes it).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "config/config.h"
#include "drivers/driver_context.h"

namespace hapticd::drivers::evdev {

// The kernel's input ABI, as linux/input-event-codes.h and linux/input.h define it.
inline constexpr int kEvSyn = 0x00, kEvAbs = 0x03, kEvFf = 0x15, kEvFfStatus = 0x17;
inline constexpr int kSynReport = 0, kSynDropped = 3;
inline constexpr int kFfConstant = 0x52, kFfGain = 0x60, kFfAutocenter = 0x61;
inline constexpr int kFfStatusStopped = 0, kFfStatusPlaying = 1;
inline constexpr int kAbsMax = 0x3f;
inline constexpr int kLevelMax = 0x7fff;  // |ff_constant_effect.level|
// ff_effect.direction for `degrees`: 0x0000 down, 0x4000 (90) left, 0x8000 up, 0xC000 right
// (<linux/input.h>): the way a positive level pushes.
std::uint16_t direction_of(double degrees) noexcept;

// The kernel force-feedback driver the device is bound to, by what it does with an update of
// the effect (docs/drivers/evdev.md, "Delay"):
//   uinput   a device in user space: EVIOCSFF returns once that process took the effect
//   pidff    hid-pidff (and drivers like it): one HID report per changed level, on USB
//   memless  ff-memless (hid-lgff, hid-lg4ff, hid-tmff, xpad...): the update is played from a
//            kernel timer at the next jiffy, then sent over USB
enum class FfDriver : std::uint8_t { kUinput, kPidff, kMemless };
const char* to_string(FfDriver d) noexcept;

// Which input device: every key given must match; `path` alone overrides the rest.
struct Selector {
  std::string name;  // the device's name (EVIOCGNAME), exactly
  std::optional<std::uint16_t> vendor_id, product_id;
  std::string phys;  // EVIOCGPHYS, e.g. usb-0000:00:14.0-2/input0
  std::string uniq;  // EVIOCGUNIQ: the serial number where the device has one
  std::string path;  // /dev/input/eventN or a /dev/input/by-id/ link to it
  bool empty() const noexcept {
    return name.empty() && !vendor_id && !product_id && phys.empty() && uniq.empty() &&
           path.empty();
  }
};

// How the axis' raw value becomes a position.
enum class Scale : std::uint8_t {
  kRange,       // linearly from the axis' [minimum, maximum] onto [min, max]
  kResolution,  // value / resolution: the kernel's units per mm (linear) or per rad (rotary)
};

struct AxisSettings {
  int code = 0;  // ABS_X
  Scale scale = Scale::kRange;
  double min = 0.0, max = 0.0;  // kRange: the positions (m or rad) at minimum and maximum
  bool rotary = false;          // kResolution: units per rad (true) or per mm (false)
  double offset = 0.0;          // kResolution: added to value / resolution
  // The device's value is a counter that passes its maximum and continues at its minimum (a
  // multi-turn encoder in a report field of its own width): unwrapped from the previous
  // sample. The kernel's range must then hold 2^n values (docs/drivers/evdev.md).
  bool wraps = false;
  // Two axes (device.evdev.axes[i].direction_deg): the ff_effect.direction toward which a
  // positive force on this joint pushes, 0 (down, +Y), 90 (left, -X), 180 (up, -Y) or 270
  // (right, +X); the two axes' are perpendicular. One axis: the section's direction_deg.
  double direction_deg = 270.0;
};

// How the force of two axes becomes FF_CONSTANT effects (device.evdev.effect,
// docs/drivers/evdev.md "Two axes"):
//   kDirection  one effect whose direction and level follow the force vector each tick
//   kPerAxis    one effect per axis at that axis' fixed direction, its signed level the joint's
enum class EffectMode : std::uint8_t { kDirection, kPerAxis };
const char* to_string(EffectMode m) noexcept;

struct EvdevSettings final : config::DriverSettings {
  Selector select;
  AxisSettings axis;                           // joint 0: device.evdev.axis, or axes[0]
  AxisSettings second;                         // joint 1 where device.evdev.axes has two entries
  int joints = 1;                              // 1 (axis) or 2 (axes)
  EffectMode effect = EffectMode::kDirection;  // two axes only
  const AxisSettings& axis_of(int joint) const noexcept { return joint == 0 ? axis : second; }
  double force_full_scale = 0.0;  // N (N m) at level 0x7fff, >= device.max_force
  double direction_deg = 270.0;   // ff_effect.direction: 270 (0xC000, right) pushes toward +x
  double gain = 1.0;              // FF_GAIN while output is on, (0, 1]
  double autocenter = 0.0;        // FF_AUTOCENTER while output is off, [0, 1]; 0 while on
  FfDriver ff_driver = FfDriver::kPidff;
  double poll_interval_ms = 1.0;  // pidff, memless: the USB endpoints' polling interval
  int kernel_hz = 250;            // memless: the kernel's timer frequency (Debian: 250)
  // No axis event for this long while a non-zero force is commanded: the loop's stale data
  // (a device that hangs without being unplugged). 0: no bound, the default: through evdev a
  // device held still cannot be told from one that hangs (docs/drivers/evdev.md).
  double liveness_ms = 0.0;
  // The longest the device takes to take an update of the effect (EVIOCSFF returns then: a
  // device in user space answers each upload itself). Declared as delay; an update measured
  // longer than the declared delay covers is late, and late_update_fault of them in a row
  // fault the loop.
  double update_latency_ms = 0.0;
  int late_update_fault = 10;
  int writer_priority = 1;  // SCHED_FIFO of the update thread (loop.rt_priority - 1)
};

// The axis range the kernel reports (EVIOCGABS).
struct AxisRange {
  int minimum = 0, maximum = 0, resolution = 0;
};

// "ABS_X" -> 0 ... "ABS_MISC" -> 0x28; ABS_MT_* are not single axes and are not named.
std::optional<int> abs_code(std::string_view name) noexcept;
// The name of `code`, or "ABS_0xNN" for one without a name here.
std::string abs_name(int code);

// RT-safe. The axis value in SI (m or rad); an unwrapped value may lie beyond the range.
// kRange needs maximum != minimum, kResolution a resolution > 0 (configure checks both).
double axis_position(std::int64_t value, const AxisSettings& axis, const AxisRange& range) noexcept;
// The width n of a counter whose values fill the range: maximum - minimum + 1 = 2^n (1..32),
// or 0 when they do not (such an axis cannot be unwrapped: axis.wraps refuses it).
int counter_bits(const AxisRange& range) noexcept;

// RT-safe. The FF_CONSTANT level for `force`: force / full_scale of 0x7fff, rounded and held
// within +-0x7fff (a non-finite force reads 0; the Device never passes one on).
std::int16_t force_level(double force, double full_scale) noexcept;
// The force a level stands for.
double level_force(int level, double full_scale) noexcept;

// The unit vector in the effect's plane (x right, y down) toward which ff_effect.direction
// `direction` points, as <linux/input.h> encodes it: 0x0000 down (+y), 0x4000 left (-x), 0x8000
// up (-y), 0xC000 right (+x), i.e. (-sin, cos) of the direction's angle; ff-memless renders the
// same, its x = sin * level and y = -cos * level counted toward left and up (ml_combine_effects).
struct PlaneVector {
  double x = 0.0, y = 0.0;
};
PlaneVector direction_vector(std::uint16_t direction) noexcept;
// The one effect of two axes (EffectMode::kDirection): its direction and level.
struct DirectedLevel {
  std::uint16_t direction = 0;
  std::int16_t level = 0;
};
// RT-safe. The direction and level that push joint j with force[j] (N), each joint along its
// axis' direction_deg: the vector's direction rounded to 1/65536 of a turn, its length as
// force_level. A force rounding to level 0 keeps `previous`'s direction (hid-pidff sends a Set
// Effect report for every change of direction, none for the level alone).
DirectedLevel directed_level(double force0, double force1, const EvdevSettings& s,
                             std::uint16_t previous) noexcept;
// RT-safe. The force (N) an effect of `direction` and `level` (times gain) puts on the device's
// axis that joint j's direction_deg lies along (x for 90 and 270, y for 0 and 180), counted
// toward that axis' + (right, down): what a device following <linux/input.h> renders.
double plane_force(int joint, std::uint16_t direction, int level, const EvdevSettings& s) noexcept;

// Whole samples between write() and the force acting, as the gate analyses them
// (docs/drivers/evdev.md): what the kernel's driver adds - uinput 0; pidff like the HID
// driver, ceil(2 P / T) - 1; memless one timer tick more, ceil((2 P + 1/HZ) / T) - 1 - plus
// what the update itself takes, L = update_latency_ms: a level can wait behind the update
// before it (up to L) and then take L, ceil(2 L / T) - 1 (0 while L <= T/2).
int declared_delay_samples(const EvdevSettings& s, double sample_period_s) noexcept;
// The longest update the declared delay covers: (d_L + 1) T / 2, d_L the samples it adds for
// update_latency_ms. An update measured longer is late (T/2 when update_latency_ms is 0).
double covered_update_s(const EvdevSettings& s, double sample_period_s) noexcept;
// The highest loop rate whose every update can reach the device: memless plays at most one
// update per timer tick (kernel_hz); the others are bounded by the USB polling interval
// (1000 / poll_interval_ms); uinput by nothing of the kernel's (0: none).
double highest_rate_hz(const EvdevSettings& s) noexcept;

}  // namespace hapticd::drivers::evdev

namespace hapticd::drivers::evdev {
// The section of a configuration whose device.driver is evdev; throws std::logic_error for
// another driver's.
const EvdevSettings& evdev_settings(const DriverContext& ctx);
}  // namespace hapticd::drivers::evdev
