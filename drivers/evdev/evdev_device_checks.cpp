// What configure checks of the device the kernel offers (each axis, its fuzz, force feedback, gain
// and autocenter where the configuration needs them, a counter's range for axis.wraps, the kind of
// its kernel driver), and the sentences the driver's faults are named with.
#include <cerrno>
#include <cstdio>

#include "base/errno_text.h"
#include "config/schema_reader.h"
#include "drivers/evdev/evdev_device.h"

namespace hapticd::drivers::evdev {

void EvdevDevice::check_device(const wire::Facts& f, const AxisSettings& a) const {
  const std::string who = "evdev: \"" + f.name + "\"";
  if (!f.has_axis) throw DeviceError(who + " has no " + abs_name(a.code) + " axis");
  if (!f.ff_constant) {
    throw DeviceError(who +
                      " offers no FF_CONSTANT force feedback (`hapticd devices` lists "
                      "the devices that do)");
  }
  if (f.ff_effects < 1) throw DeviceError(who + " holds no force-feedback effect");
  if (a.scale == Scale::kRange && f.range.maximum <= f.range.minimum) {
    throw DeviceError(who + ": the kernel gives " + abs_name(a.code) + " the range [" +
                      std::to_string(f.range.minimum) + ", " + std::to_string(f.range.maximum) +
                      "], which cannot be mapped onto device.evdev.axis.min..max");
  }
  if (a.scale == Scale::kResolution && f.range.resolution <= 0) {
    throw DeviceError(who + ": the kernel gives " + abs_name(a.code) +
                      " no resolution: use device.evdev.axis.scale range with min and max");
  }
  if (settings_->gain < 1.0 && !f.ff_gain) {
    throw DeviceError(who + " has no FF_GAIN: device.evdev.gain must be 1");
  }
  if (settings_->autocenter > 0.0 && !f.ff_autocenter) {
    throw DeviceError(who + " has no FF_AUTOCENTER: device.evdev.autocenter must be 0");
  }
}

// A device whose value is a counter of its report field's width: the kernel passes the field's
// value as it is, neither clamped nor wrapped (<linux/input.h>, struct input_absinfo: "input
// core does not clamp reported values to the [minimum, maximum] limits"), so the counter's
// rollover reaches the driver as a jump of the whole range. Unwrapped, the range must hold 2^n
// values, as a field of n bits does.
void EvdevDevice::check_wrap(const wire::Facts& f, int j) {
  const AxisSettings& a = settings_->axis_of(j);
  if (!a.wraps) return;
  const int bits = counter_bits(f.range);
  if (bits == 0) {
    throw DeviceError("evdev: \"" + f.name +
                      "\": device.evdev.axis.wraps needs a counter's range, " +
                      "2^n values, but the kernel gives " + abs_name(a.code) + " [" +
                      std::to_string(f.range.minimum) + ", " + std::to_string(f.range.maximum) +
                      "]: it cannot be unwrapped");
  }
  axes_[j].unwrap = io::CounterUnwrap(bits, false);  // a new session: the first value is the base
}

// The kernel smooths an axis with fuzz (hid-input gives a joystick's 1/256 of its range): a
// change within fuzz/2 is dropped and up to twice fuzz averaged with the last value, a dead
// band and a lag in the position the wall is rendered from. hapticd turns it off while it has
// the device and gives it back at close.
void EvdevDevice::unfuzz(int j, int fuzz) {
  axes_[j].kernel_fuzz = 0;
  if (fuzz == 0) return;
  const int code = settings_->axis_of(j).code;
  transport_->set_fuzz(code, 0);
  axes_[j].kernel_fuzz = fuzz;
  notices_.push_back("the kernel filtered " + abs_name(code) + " with fuzz " +
                     std::to_string(fuzz) + " (changes within " + std::to_string(fuzz / 2) +
                     " counts dropped): hapticd sets it to 0 while it runs and gives it back at "
                     "close");
}

void EvdevDevice::refuzz() noexcept {
  for (int j = 0; transport_ && j < joints_; ++j) {
    if (axes_[j].kernel_fuzz == 0) continue;
    try {
      transport_->set_fuzz(settings_->axis_of(j).code, axes_[j].kernel_fuzz);
    } catch (const DeviceError&) {
      // A device that is gone takes its fuzz with it.
    }
    axes_[j].kernel_fuzz = 0;
  }
}

void EvdevDevice::note_kernel_driver(const InputListing& l) {
  const std::optional<FfDriver> guess = guess_ff_driver(l);
  const std::string configured = to_string(settings_->ff_driver);
  if (!guess) {
    notices_.push_back("kernel driver '" + l.kernel_driver +
                       "' is not one hapticd knows: check that its force feedback is what "
                       "device.evdev.ff_driver " +
                       configured +
                       " says, or the declared delay is wrong (docs/drivers/evdev.md)");
  } else if (*guess != settings_->ff_driver) {
    notices_.push_back(std::string("the device is bound to kernel driver '") +
                       (l.virtual_device ? std::string("uinput") : l.kernel_driver) +
                       "', whose force feedback is " + to_string(*guess) +
                       ", but device.evdev.ff_driver says " + configured + ": the gate analyses " +
                       configured + "'s delay (docs/drivers/evdev.md)");
  }
}

std::string EvdevDevice::describe_late() const {
  using config::schema::format_number;
  const int d = declared_delay_samples(*settings_, period_s_);
  char took[32], covered[32];
  std::snprintf(took, sizeof took, "%.1f", static_cast<double>(late_ns_) * 1e-6);
  std::snprintf(covered, sizeof covered, "%.1f", covered_update_s(*settings_, period_s_) * 1e3);
  return std::string("evdev: the device took up to ") + took + " ms to take an update, " +
         std::to_string(settings_->late_update_fault) + " in a row longer than the " + covered +
         " ms the declared delay covers (device.evdev.update_latency_ms " +
         format_number(settings_->update_latency_ms) + ", " + std::to_string(d) +
         " samples declared): the gate's analysis no longer holds; raise update_latency_ms "
         "(the run's longest_update_us says what it measured)";
}

std::string EvdevDevice::describe(const DeviceFault& fault) const {
  if (fault.fault_class == FaultClass::kDevice) {
    return "evdev: the device stopped hapticd's force-feedback effect itself (EV_FF_STATUS "
           "stopped)";
  }
  if (fault.code == kUpdatesLate) return describe_late();
  const int e = static_cast<int>(fault.code);
  if (e == ENODEV || e == EIO || e == ESHUTDOWN) {
    return std::string("evdev: the device is gone (") + base::errno_text(e) +
           "): unplugged or reset?";
  }
  return std::string("evdev: the device failed: ") + base::errno_text(e);
}

}  // namespace hapticd::drivers::evdev
