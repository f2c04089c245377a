// The GPIO driver's entry in the registry (drivers/registry.h): device.gpio, the declared
// delay from the PWM period and T, the device on the kernel's lines and sysfs PWM, the
// device against its loopback peer, and the peer on gpio-sim and the PWM simulator.
#pragma once

#include "drivers/registry.h"

namespace hapticd::drivers::gpio {

DriverEntry gpio_driver();

}  // namespace hapticd::drivers::gpio
