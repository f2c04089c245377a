// Reads device.hid (the HID driver's section) with the config library's schema reader, so
// every problem is reported as "FILE:LINE: device.hid.key: what" and an unknown key is never
// silently ignored. Validation that spans keys (overlapping fields, fields past the report,
// a force scale that cannot reach device.max_force) is reported at the key that must change.
#pragma once

#include <memory>

#include "config/config.h"
#include "config/schema_reader.h"

namespace hapticd::drivers::hid {

// Not RT-safe. The HidSettings, or null after reporting every problem through `section`.
std::shared_ptr<const config::DriverSettings> read_hid_section(config::schema::MapReader& section,
                                                               const config::Config& cfg);

}  // namespace hapticd::drivers::hid
