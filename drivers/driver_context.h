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

}  // namespace hapticd::drivers
