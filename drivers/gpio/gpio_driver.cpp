#include "drivers/gpio/gpio_driver.h"

#include "drivers/gpio/gpio_device.h"
#include "drivers/gpio/kernel_transport.h"
#include "drivers/gpio/loopback_transport.h"

namespace hapticd::drivers::gpio {
namespace {

int delay(const DriverContext& ctx) {
  return declared_delay_samples(gpio_settings(ctx), ctx.sample_period_s());
}

std::unique_ptr<Device> make_device(const DriverContext& ctx) {
  const GpioSettings& s = gpio_settings(ctx);
  return std::make_unique<GpioDevice>(s, ctx.max_force, std::make_unique<KernelTransport>(s),
                                      delay(ctx));
}

std::unique_ptr<Device> make_loopback_device(const DriverContext& ctx, io::UniqueFd end) {
  const GpioSettings& s = gpio_settings(ctx);
  return std::make_unique<GpioDevice>(
      s, ctx.max_force, std::make_unique<LoopbackTransport>(std::move(end), s.joints.size()),
      delay(ctx));
}

// The direction line's level for a positive force (docs/drivers/gpio.md): joint 0's, the joint
// the direction check pushes (several joints: the check is off, docs/kinematics.md).
ForceReversal force_reversal(const config::Config& cfg) {
  const GpioSettings& s = gpio_settings(cfg);
  const bool high = s.joint(0).direction_positive_high;
  return {s.listed ? "device.gpio.joints[0].direction_positive" : "device.gpio.direction_positive",
          high ? "high" : "low", high ? "low" : "high"};
}

}  // namespace

DeviceEntry device_entry() {
  DeviceEntry e;
  e.udev_rules = &write_udev_rules;
  e.name = "gpio";
  e.summary = "quadrature encoder on GPIO lines (libgpiod) and a sysfs PWM motor driver";
  e.read_section = &read_gpio_section;
  e.declared_delay = &delay;
  e.make_device = &make_device;
  e.make_loopback_device = &make_loopback_device;
  e.force_reversal = &force_reversal;
  return e;
}

}  // namespace hapticd::drivers::gpio
