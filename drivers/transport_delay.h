// The transport delay each driver declares (DESIGN.md §6), known without opening hardware so
// `hapticd check` analyses the loop that `run` would execute. Each driver's
// Device::transport_delay_samples() returns its entry here.
#pragma once

#include "config/config.h"

namespace hapticd {

constexpr int declared_transport_delay(config::DriverKind driver) noexcept {
  switch (driver) {
    case config::DriverKind::kSim:
      return 0;  // in-process: the force written at tick k acts from sample k
    case config::DriverKind::kHid:
      return 1;  // interrupt OUT report takes effect one USB frame later
    case config::DriverKind::kCan:
      return 1;  // synchronous RPDO takes effect at the next SYNC
    case config::DriverKind::kGpio:
      return 0;  // sysfs PWM write takes effect immediately
  }
  return 0;
}

}  // namespace hapticd
