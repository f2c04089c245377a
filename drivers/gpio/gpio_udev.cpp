#include <algorithm>
#include <vector>

#include "config/config_loader.h"
#include "drivers/gpio/gpio_driver.h"
#include "drivers/gpio/gpio_settings.h"

namespace hapticd::drivers::gpio {
namespace {

std::string chip_kernel_name(const config::Config& cfg, const GpioSettings& s, std::size_t i) {
  const std::string& chip = s.joint(i).chip;
  const std::string name = chip.rfind("/dev/", 0) == 0 ? chip.substr(5) : chip;
  const bool numbered = name.size() > 8 && name.rfind("gpiochip", 0) == 0 &&
                        name.find_first_not_of("0123456789", 8) == std::string::npos;
  if (numbered) return name;
  const std::string key = s.key(i, "chip");
  throw config::ConfigError(
      {cfg.locate(key) + ": " + key + ": '" + chip +
       "' is not a chip's kernel name, and udev matches a GPIO chip by that name only: give it "
       "as gpiochipN (the `gpiodetect` line that shows this label)"});
}

// Joint i's one channel: exported by udev as root, its files granted to the group.
void pwm_rules(const GpioSettings& s, std::size_t i, UdevRules& out) {
  const GpioJointSettings& j = s.joint(i);
  const std::string pwmchip = "pwmchip" + std::to_string(j.pwm_chip);
  const std::string ch = "pwm" + std::to_string(j.pwm_channel);
  const std::string files = "period duty_cycle polarity enable";
  out.comment(s.key(i, "pwm") + ": channel " + std::to_string(j.pwm_channel) + " of " + pwmchip +
              ", exported by udev as root; the group gets its period, duty_cycle, polarity and "
              "enable. The chip's export and unexport stay root's: no other channel can be "
              "taken or released.");
  out.rule("ACTION==\"add|change\", SUBSYSTEM==\"pwm\", KERNEL==\"" + pwmchip +
           "\", ENV{UNEXPORT}==\"\", RUN+=\"/bin/sh -c 'test -d %S%p/" + ch + " || echo " +
           std::to_string(j.pwm_channel) + " >%S%p/export; cd %S%p/" + ch + " && chgrp " +
           out.group() + " " + files + " && chmod g+w " + files + "'\"");
}

// The lines of every joint on `chip`, for the rule's comment.
std::string lines_on(const GpioSettings& s, const std::vector<std::string>& names,
                     const std::string& chip) {
  std::string lines;
  for (std::size_t i = 0; i < s.joints.size(); ++i) {
    if (names[i] != chip) continue;
    const GpioJointSettings& j = s.joint(i);
    lines += (lines.empty() ? "" : ", ") + std::to_string(j.line_a) + ", " +
             std::to_string(j.line_b) + ", " + std::to_string(j.line_direction);
    if (j.line_index) lines += ", " + std::to_string(*j.line_index);
    if (j.line_fault) lines += ", " + std::to_string(*j.line_fault);
  }
  return lines;
}

}  // namespace

// One rule per GPIO chip the joints use (each granted once), one per joint's PWM channel.
void write_udev_rules(const config::Config& cfg, UdevRules& out) {
  const auto& s = gpio_settings(cfg);
  std::vector<std::string> names;
  for (std::size_t i = 0; i < s.joints.size(); ++i) names.push_back(chip_kernel_name(cfg, s, i));
  for (std::size_t i = 0; i < s.joints.size(); ++i) {
    if (std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), names[i]) !=
        names.begin() + static_cast<std::ptrdiff_t>(i)) {
      continue;  // granted with an earlier joint's
    }
    out.comment(s.key(i, "chip") + ": " + names[i] +
                ". A GPIO chip is granted whole: whoever opens it may request any of its lines "
                "no one holds. This instance uses lines " +
                lines_on(s, names, names[i]) + " (docs/operations.md).");
    out.rule("SUBSYSTEM==\"gpio\", KERNEL==\"" + names[i] + "\"" + out.grant());
  }
  if (s.pwm_sysfs_root != "/sys/class/pwm") {
    out.comment("device.gpio.pwm.sysfs_root is " + s.pwm_sysfs_root +
                ", not /sys/class/pwm: udev has no PWM chip to set up there.");
    return;
  }
  for (std::size_t i = 0; i < s.joints.size(); ++i) pwm_rules(s, i, out);
}

}  // namespace hapticd::drivers::gpio
