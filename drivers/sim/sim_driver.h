// The sim driver's entry in the registry: no section of its own (the plant is device.sim,
// which every loopback peer shares), no transport delay, and always its own loopback peer.
#pragma once

#include "drivers/registry.h"

namespace hapticd::drivers::sim_driver {

DriverEntry sim_driver();

}  // namespace hapticd::drivers::sim_driver
