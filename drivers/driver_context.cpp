#include "drivers/driver_context.h"

#include <algorithm>
#include <cmath>

namespace hapticd::drivers {

DriverContext::DriverContext(const config::Config& cfg)
    : settings(cfg.device.settings),
      period_ns(cfg.loop.period_ns()),
      rt_priority(cfg.loop.rt_priority),
      realtime(cfg.loop.clock == config::ClockMode::kRealtime) {
  for (std::size_t i = 0; i < max_force.size(); ++i) max_force[i] = cfg.device.max_force[i];
}

int round_trip_delay_samples(double one_way_ms, double sample_period_s) noexcept {
  // The round trip in periods, rounded up; a hair of tolerance so 2 ms / 1 ms is 2, not 3.
  const double periods = 2.0 * one_way_ms * 1e-3 / sample_period_s;
  const int round_trip = static_cast<int>(std::ceil(periods - 1e-9));
  return std::max(0, round_trip - 1);
}

}  // namespace hapticd::drivers
