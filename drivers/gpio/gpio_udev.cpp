#include "config/config_loader.h"
#include "drivers/gpio/gpio_driver.h"
#include "drivers/gpio/gpio_settings.h"

namespace hapticd::drivers::gpio {
namespace {

std::string chip_kernel_name(const config::Config& cfg, const std::string& chip) {
  const std::string name = chip.rfind("/dev/", 0) == 0 ? chip.substr(5) : chip;
  const bool numbered = name.size() > 8 && name.rfind("gpiochip", 0) == 0 &&
                        name.find_first_not_of("0123456789", 8) == std::string::npos;
  if (numbered) return name;
  throw config::ConfigError(
      {cfg.locate("device.gpio.chip") + ": device.gpio.chip: '" + chip +
       "' is not a chip's kernel name, and udev matches a GPIO chip by that name only: give it "
       "as gpiochipN (the `gpiodetect` line that shows this label)"});
}

// The PWM chip's one channel: exported by udev as root, its files granted to the group.
void pwm_rules(const GpioSettings& s, UdevRules& out) {
  if (s.pwm_sysfs_root != "/sys/class/pwm") {
    out.comment("device.gpio.pwm.sysfs_root is " + s.pwm_sysfs_root +
                ", not /sys/class/pwm: udev has no PWM chip to set up there.");
    return;
  }
  const std::string pwmchip = "pwmchip" + std::to_string(s.pwm_chip);
  const std::string ch = "pwm" + std::to_string(s.pwm_channel);
  const std::string files = "period duty_cycle polarity enable";
  out.comment("device.gpio.pwm: channel " + std::to_string(s.pwm_channel) + " of " + pwmchip +
              ", exported by udev as root; the group gets its period, duty_cycle, polarity and "
              "enable. The chip's export and unexport stay root's: no other channel can be "
              "taken or released.");
  out.rule("ACTION==\"add|change\", SUBSYSTEM==\"pwm\", KERNEL==\"" + pwmchip +
           "\", ENV{UNEXPORT}==\"\", RUN+=\"/bin/sh -c 'test -d %S%p/" + ch + " || echo " +
           std::to_string(s.pwm_channel) + " >%S%p/export; cd %S%p/" + ch + " && chgrp " +
           out.group() + " " + files + " && chmod g+w " + files + "'\"");
}

}  // namespace

void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const auto& s = gpio_settings(cfg);
  const std::string chip = chip_kernel_name(cfg, s.chip);
  std::string lines = std::to_string(s.line_a) + ", " + std::to_string(s.line_b) + ", " +
                      std::to_string(s.line_direction);
  if (s.line_index) lines += ", " + std::to_string(*s.line_index);
  if (s.line_fault) lines += ", " + std::to_string(*s.line_fault);
  out.comment("device.gpio.chip: " + chip +
              ". A GPIO chip is granted whole: whoever opens it may request any of its lines no "
              "one holds. This instance uses lines " +
              lines + " (docs/operations.md).");
  out.rule("SUBSYSTEM==\"gpio\", KERNEL==\"" + chip + "\"" + out.grant());
  pwm_rules(s, out);
}

}  // namespace hapticd::drivers::gpio
