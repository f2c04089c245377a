#include "drivers/driver_context.h"

namespace hapticd::drivers {

DriverContext::DriverContext(const config::Config& cfg)
    : settings(cfg.device.settings),
      period_ns(cfg.loop.period_ns()),
      rt_priority(cfg.loop.rt_priority),
      realtime(cfg.loop.clock == config::ClockMode::kRealtime) {
  for (std::size_t i = 0; i < max_force.size(); ++i) max_force[i] = cfg.device.max_force[i];
}

}  // namespace hapticd::drivers
