// device.gpio: the GPIO driver's section (docs/drivers/gpio.md, config/gpio.yaml), read with
// the config library's schema reader so its messages read "FILE:LINE: device.gpio.x: what".
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/driver_schema.h"
#include "drivers/driver_context.h"

namespace hapticd::drivers::gpio {

// The missed-edge tolerance is a window of that many edge times, preallocated.
inline constexpr long long kMaxMissedEdgeFault = 10000;

// One joint's encoder, motor-driver lines and PWM channel: the one-joint keys of device.gpio,
// or one entry of device.gpio.joints (joint i is entry i).
struct GpioJointSettings {
  // The GPIO chip: a path ("/dev/gpiochip0"), a name ("gpiochip0") or the chip's label.
  std::string chip = "gpiochip0";
  unsigned line_a = 0;
  unsigned line_b = 1;
  std::optional<unsigned> line_index;   // re-zeroes the count on its rising edge
  unsigned line_direction = 2;          // output: the motor driver's direction input
  std::optional<unsigned> line_fault;   // input: the motor driver's fault output (nFAULT)
  bool direction_positive_high = true;  // the direction line's level for a positive force

  double counts_per_unit = 1.0e5;  // x4 counts per m (or rad); negative: counts down as x grows
  std::int64_t start_count = 0;    // the count assumed at configure (a relative encoder)
  std::int64_t index_count = 0;    // the count the index sets

  unsigned pwm_chip = 0;
  unsigned pwm_channel = 0;
};

struct GpioSettings final : config::DriverSettings {
  // One entry per joint, never empty: the one-joint form fills joints[0].
  std::vector<GpioJointSettings> joints{GpioJointSettings{}};
  // Whether the configuration gave device.gpio.joints (the names its messages use).
  bool listed = false;

  // The same for every joint: the encoders and motor drivers are of one kind, and one
  // tolerance judges them all.
  bool encoder_active_low = false;  // A, B and index read inverted
  bool fault_active_low = true;     // nFAULT: pulled low on a fault
  double max_edge_rate_hz = 0.0;    // A/B edges per second; 0: no limit
  // More than missed_edge_fault missed edges within missed_edge_window_s fault the device.
  std::uint64_t missed_edge_fault = 4;  // 0..kMaxMissedEdgeFault
  double missed_edge_window_s = 1.0;    // > 0

  std::string pwm_sysfs_root = "/sys/class/pwm";
  std::uint64_t pwm_period_ns = 50'000;
  bool pwm_inversed = false;
  // No stop mode: the motor is stopped with duty 0 on the enabled channel, the one output
  // level Linux's PWM API defines (docs/drivers/gpio.md, "Stopping the motor").

  const GpioJointSettings& joint(std::size_t i) const { return joints.at(i); }
  // The configuration key of joint i's `key`: "device.gpio.joints[1].lines.a", or
  // "device.gpio.lines.a" in the one-joint form.
  std::string key(std::size_t i, const std::string& key) const;
  // "joint 1 (gpiochip1 lines 4,5, pwmchip0/pwm1)" for messages; "" in the one-joint form, whose
  // messages stay as they were.
  std::string joint_name(std::size_t i) const;
};

// The device entry's read_section for device.gpio.
std::shared_ptr<const config::DriverSettings> read_gpio_section(config::schema::MapReader& section,
                                                                const config::Config& cfg);

// The settings of a loaded configuration whose driver is gpio (throws std::logic_error
// otherwise: the registry only calls the gpio driver for such a configuration).
const GpioSettings& gpio_settings(const DriverContext& ctx);

// Whole samples between a PWM write and the force acting: the new duty waits for the running
// PWM period to end, up to one period P later; with P <= T that is within the sample period
// (0), beyond it ceil(P / T) - 1.
int declared_delay_samples(const GpioSettings& s, double sample_period_s);

}  // namespace hapticd::drivers::gpio
