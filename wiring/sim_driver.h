// The sim driver's entry: no section of its own (the plant is device.sim, which every loopback
// peer shares), no transport delay, and always in one process: the simulated device is its own
// peer (sim/sim_device.h).
#pragma once

#include "wiring/registry.h"

namespace hapticd::wiring {

DriverEntry sim_driver();

}  // namespace hapticd::wiring
