// The hapticd schema: which keys exist, what each must hold, and where it lands in Config.
// Internal to the config library.
#pragma once

#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>

#include "config/config.h"
#include "config/driver_schema.h"
#include "config/schema_reader.h"

namespace hapticd::config::schema {

// Validates the (merged) document into `config`, reporting every problem to `diag`.
// Relative paths in it resolve against `base_dir`; device.driver must name one of `drivers`.
void read_config(Diagnostics& diag, const YAML::Node& root, const std::string& base_dir,
                 const DriverSchemas& drivers, Config& config);

// Reads the profile under `key` of `parent` into `out`. When the key is absent and
// `required_by` is set, reports "parent.key: missing (required by <required_by>)".
void read_profile(MapReader& parent, std::string_view key,
                  const std::optional<std::string>& required_by, ProfileSpec& out);

}  // namespace hapticd::config::schema
