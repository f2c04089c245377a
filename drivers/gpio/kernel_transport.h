// The GPIO driver against the kernel: libgpiod lines (gpiod_lines.h) for the encoder, the
// direction and the fault line, a sysfs PWM channel (sysfs_pwm.h) for the duty.
#pragma once

#include "drivers/gpio/gpio_settings.h"
#include "drivers/gpio/gpio_transport.h"
#include "drivers/gpio/gpiod_lines.h"
#include "drivers/gpio/sysfs_pwm.h"

namespace hapticd::drivers::gpio {

class KernelTransport final : public GpioTransport {
 public:
  explicit KernelTransport(const GpioSettings& settings);

  std::uint8_t open(const OutputState& off) override;
  void close() noexcept override;
  std::uint8_t read_levels() override { return lines_.read_levels(); }
  std::string describe() const override;
  EdgeRead read_edges(std::span<Edge> buffer) noexcept override;
  int write_output(const OutputState& out) noexcept override;
  void emergency_stop() noexcept override { pwm_.emergency_stop(); }

  const SysfsPwm& pwm() const noexcept { return pwm_; }

 private:
  std::string chip_;
  LineOffsets offsets_;
  PwmChannel channel_;
  GpiodLines lines_;
  SysfsPwm pwm_;
  bool direction_level_ = false;
};

}  // namespace hapticd::drivers::gpio
