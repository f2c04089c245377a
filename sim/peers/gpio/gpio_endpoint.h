// Where the GPIO peer may play (sim/peers/endpoint_verdict.h): the directory it writes its
// lines' pull attributes under, the first half of its endpoint, must be a gpio-sim chip's
// sysfs directory, /sys/devices/platform/gpio-sim.N/gpiochipM. Not RT code.
#pragma once

#include <string>

#include "config/config.h"
#include "sim/peers/endpoint_verdict.h"

namespace hapticd::sim::gpio {

struct GpioChipFacts {
  bool exists = false;
  bool is_gpio_chip = false;  // a device on the gpio bus (its `subsystem` is /sys/bus/gpio)
  std::string driver;         // the driver of the device the chip belongs to; "" none
};

// The directory's device: whether it is on the gpio bus, and its parent device's driver.
GpioChipFacts read_gpio_chip(const std::string& chip_dir);
// Pure.
EndpointVerdict judge_gpio_chip(const std::string& chip_dir, const GpioChipFacts& facts);
// The peer entry's judge_endpoint: the chip directory before the endpoint's comma.
EndpointVerdict judge_endpoint(const config::Config& cfg, const std::string& endpoint);

}  // namespace hapticd::sim::gpio
