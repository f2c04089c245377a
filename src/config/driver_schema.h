// How the loader reads a driver's own section, device.<driver>, without knowing the driver:
// the driver registry (wiring/registry.h) hands the loader one DriverSchema per driver this
// build has, and the selected driver's code parses its section with the same reader and the
// same "FILE:LINE: key: what" messages as the rest of the file.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "config/config.h"
#include "config/schema_reader.h"

namespace hapticd::config {

struct DriverSchema {
  std::string name;  // the value of device.driver that selects it
  // Reads device.<name> (an empty mapping when the file has none) and returns the driver's
  // settings, reporting every problem through the reader; null when there were problems.
  // `cfg` holds what was read before it: loop.* and device.{mass, damping, max_force, sim}.
  // Empty for a driver without a section of its own.
  std::function<std::shared_ptr<const DriverSettings>(schema::MapReader& section,
                                                      const Config& cfg)>
      read_section;
};

using DriverSchemas = std::vector<DriverSchema>;

// The simulated device alone: what the loader knows without the driver registry (tests of
// the config library, and the plant section device.sim that every loopback peer shares).
const DriverSchemas& sim_driver_only();

}  // namespace hapticd::config
