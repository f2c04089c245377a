// The GPIO driver against the kernel: libgpiod lines (gpiod_lines.h) for the encoders, the
// direction and the fault lines, one GpiodLines per chip holding every line of the joints on
// it; a sysfs PWM channel (sysfs_pwm.h) per joint for the duty.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "drivers/gpio/gpio_settings.h"
#include "drivers/gpio/gpio_transport.h"
#include "drivers/gpio/gpiod_lines.h"
#include "drivers/gpio/sysfs_pwm.h"

namespace hapticd::drivers::gpio {

class KernelTransport final : public GpioTransport {
 public:
  explicit KernelTransport(const GpioSettings& settings);

  JointLevels open(std::span<const OutputState> off) override;
  void close() noexcept override;
  JointLevels read_levels() override;
  std::string describe() const override;
  EdgeRead read_edges(std::span<Edge> buffer) noexcept override;
  int write_output(const OutputState& out) noexcept override;
  void emergency_stop() noexcept override;

  const SysfsPwm& pwm(std::size_t joint = 0) const noexcept { return joints_[joint].pwm; }

 private:
  // The joints whose lines are on one chip, in one GpiodLines.
  struct Chip {
    std::string name;
    std::vector<LineOffsets> joints;
    std::unique_ptr<GpiodLines> lines;  // stable address: Joint points at it
  };
  struct Joint {
    PwmChannel channel;
    SysfsPwm pwm;
    GpiodLines* lines = nullptr;
    bool direction_level = false;
  };

  std::vector<Chip> chips_;
  std::array<Joint, base::kMaxJoints> joints_;
  std::size_t joint_count_ = 1;
};

}  // namespace hapticd::drivers::gpio
