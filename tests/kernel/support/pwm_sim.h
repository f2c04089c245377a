// The PWM chip of hapticd's own simulator module (tools/kernel-vm/pwm-sim), loaded in the
// kernel test machine. A driver drives it through the ordinary sysfs PWM interface under
// chip_path() (export, period, duty_cycle, polarity, enable); the fixture reads back, as a
// peer would, what the PWM core last applied to a channel, and can wait for the next apply.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace hapticd::kernel_test {

struct PwmApplied {
  std::uint64_t period_ns = 0;
  std::uint64_t duty_cycle_ns = 0;
  bool inversed = false;
  bool enabled = false;
  std::uint64_t applies = 0;  // how many times the core applied a (changed) state
};

class PwmSim {
 public:
  PwmSim();  // finds the simulator's chip; throws when the module is not loaded

  // /sys/class/pwm/pwmchipN: the sysfs PWM root a driver is configured with.
  const std::string& chip_path() const noexcept { return chip_path_; }
  unsigned npwm() const;

  PwmApplied applied(unsigned channel) const;
  // Waits until the channel's apply count exceeds AFTER and returns that state, using poll()
  // on the channel file (the module notifies it on every apply); nothing within TIMEOUT.
  std::optional<PwmApplied> wait_applied(unsigned channel, std::uint64_t after,
                                         std::chrono::milliseconds timeout) const;

 private:
  std::string channel_file(unsigned channel) const;

  std::string device_;     // /sys/devices/platform/hapticd-pwm-sim
  std::string chip_path_;  // /sys/class/pwm/pwmchipN
};

}  // namespace hapticd::kernel_test
