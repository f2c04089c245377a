// Reads device.evdev (the evdev driver's section) with the config library's schema reader, so
// every problem is reported as "FILE:LINE: device.evdev.key: what" and an unknown key is never
// silently ignored. What spans keys (a full scale below device.max_force, a loop rate the
// kernel driver cannot pass on) is reported at the key that must change.
#pragma once

#include <memory>

#include "config/config.h"
#include "config/schema_reader.h"

namespace hapticd::drivers::evdev {

// Not RT-safe. The EvdevSettings, or null after reporting every problem through `section`.
std::shared_ptr<const config::DriverSettings> read_evdev_section(config::schema::MapReader& section,
                                                                 const config::Config& cfg);

}  // namespace hapticd::drivers::evdev
