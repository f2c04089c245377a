#include "drivers/driver_context.h"

namespace hapticd::drivers {

DriverContext::DriverContext(const config::Config& cfg)
    : settings(cfg.device.settings),
      period_ns(cfg.loop.period_ns()),
      rt_priority(cfg.loop.rt_priority),
      realtime(cfg.loop.clock == config::ClockMode::kRealtime) {
  max_force.fill(cfg.device.max_force);
}

}  // namespace hapticd::drivers
