// The hapticd schema: which keys exist, what each must hold, and where it lands in Config.
// Internal to the config library.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config/config.h"
#include "config/driver_schema.h"
#include "config/schema_reader.h"

namespace hapticd::config::schema {

// Validates the (merged) document into `config`, reporting every problem to `diag`.
// Relative paths in it resolve against `base_dir`; device.driver must name one of `drivers`.
void read_config(Diagnostics& diag, const YAML::Node& root, const std::string& base_dir,
                 const DriverSchemas& drivers, Config& config);

// A key whose value is one of a few names, each standing for a value of E.
template <typename E>
using Options = std::vector<std::pair<std::string, E>>;

template <typename E>
std::optional<E> choice(Diagnostics& diag, const Field& field, const Options<E>& options) {
  std::vector<std::string> names;
  for (const auto& o : options) names.push_back(o.first);
  if (const auto i = read_choice(diag, field, names)) return options[*i].second;
  return std::nullopt;
}

template <typename E>
const std::string& name_of(const Options<E>& options, E value) {
  return std::find_if(options.begin(), options.end(),
                      [&](const auto& o) { return o.second == value; })
      ->first;
}

// Reads a wall's contact law (stiffness, damping, discretization, delay_samples, no_pull,
// coupling) from its mapping: `wall`'s and each of `walls`'.
void read_wall_law(MapReader& m, WallConfig& wall);

// Exactly n numbers in `f` (a field of `m`), each accepted by `ok` (`what` says what it must
// be: "> 0", "+1 or -1"), into the first n entries of `out`; `entries` names them in the
// count's message ("numbers", "numbers (one per task axis)"). Absent: false and no message. A
// wrong list: false, `out` as it was, and one message saying why.
bool read_fixed_numbers(MapReader& m, const Field& f, int n, bool (*ok)(double, const Range&),
                        const Range& range, const std::string& what, double* out,
                        const std::string& entries = "numbers");
// The same with each number in `range`, for the key `key` of `m`.
bool read_fixed_numbers(MapReader& m, std::string_view key, int n, const Range& range, double* out,
                        const std::string& entries = "numbers");

// Makes `v`, read from `f`, unit; all zeros is an error ("must point somewhere (WHAT)").
bool unit_direction(Diagnostics& d, const Field& f, const std::string& what, kinematics::Vec3& v);

// Reads `walls` of `top` for a device of `task_axes` task coordinates (walls_schema.cpp).
void read_walls(MapReader& top, int task_axes, std::vector<TaskWallConfig>& walls);

// Reads device.kinematics of `device` (kinematics_schema.cpp); absent: one joint.
void read_kinematics(MapReader& device, kinematics::Kinematics& k);

// Reads device.sim of `device` for the mechanism `k` (sim_schema.cpp): the plant and its
// operator. `rate_hz` (empty when invalid) bounds an imposed motion's frequency, `base_dir`
// resolves a replayed log's path.
void read_plant(MapReader& device, std::optional<double> rate_hz, const std::string& base_dir,
                const kinematics::Kinematics& k, SimDeviceConfig& sim_cfg);

// Reads the section `safety` of `top` (safety_schema.cpp).
void read_safety(MapReader& top, SafetyConfig& safety);

// Reads the profile under `key` of `parent` into `out`. When the key is absent and
// `required_by` is set, reports "parent.key: missing (required by <required_by>)".
void read_profile(MapReader& parent, std::string_view key,
                  const std::optional<std::string>& required_by, ProfileSpec& out);

}  // namespace hapticd::config::schema
