// What a driver is given of the configuration to build its device and declare its delay: its
// own section, the period (defined once, config::LoopConfig::period_ns), each joint's force
// limit, the RT priority and whether the loop keeps real time. Never the whole Config: a driver
// that cannot see the wall, the gate or the operator cannot come to depend on them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "base/joints.h"
#include "config/config.h"

namespace hapticd::drivers {

struct DriverContext {
  // device.<driver> as its read_section made it; null for a driver without a section.
  std::shared_ptr<const config::DriverSettings> settings;
  std::int64_t period_ns = 1'000'000;
  std::size_t joints = 1;
  std::array<double, base::kMaxJoints> max_force{};  // |u| limit of each joint (N or N m)
  int rt_priority = 80;                              // the RT thread's SCHED_FIFO priority
  bool realtime = true;                              // loop.clock: realtime (not freerun)

  DriverContext() = default;
  // Not RT-safe. What `cfg` gives its driver. Implicit on purpose: the service and the tests
  // hand a Config wherever a driver's entry is called, and the driver sees only this.
  DriverContext(const config::Config& cfg);  // NOLINT(google-explicit-constructor)

  double sample_period_s() const noexcept { return config::period_s(period_ns); }
  double rate_hz() const noexcept { return 1.0 / sample_period_s(); }

  // The driver's settings as their own type (the section the registry read for it).
  template <class Settings>
  const Settings& section() const {
    return dynamic_cast<const Settings&>(*settings);
  }
};

// Pure. Whole samples between write() and the force acting on a device behind a link of
// one-way latency `one_way_ms` (a USB interrupt endpoint's polling interval, a serial port's):
// the command waits up to that long to go out and its answer as long to come back, so the
// answer to the command of tick k is read at tick k + ceil(2 P / T), one tick later than an
// in-process device gives it: ceil(2 P / T) - 1 (1 at 1 kHz with P = 1 ms).
int round_trip_delay_samples(double one_way_ms, double sample_period_s) noexcept;

}  // namespace hapticd::drivers
