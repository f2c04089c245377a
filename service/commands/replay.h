// The engine of `hapticd replay` (docs/operations.md): a tick log's positions fed through a
// controller built from the log's own configuration - switching law at every reload marker,
// starting afresh at every re-arming, as the run did, with the passivity observer and
// controller the run had - must reproduce the logged forces bit for bit; fed through another
// configuration's controller they show what that wall would have done on the same motion (open
// loop: the positions are the logged ones). Not RT-safe.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "telemetry/log_reader.h"

namespace hapticd::service {

// One force series over the log's ordinary records and what it adds up to.
struct ForceSeries {
  std::vector<double> commanded;  // u per record (0 where the controller was not stepped)
  double max_abs_force = 0.0;     // N
  double max_penetration = 0.0;   // m, as this configuration places the wall
  std::uint64_t contact_ticks = 0;
  std::uint64_t saturated_ticks = 0;
  // Sum of u (x_k - x_{k-1}) over the stepped ticks, u the force that acted over the period,
  // as the loop counts it (J).
  double wall_energy_j = 0.0;
  // The passivity observer's minimum energy (J) and the ticks its controller damped, as the
  // loop would have seen them on these positions (the logged series: from the records).
  double min_observer_energy_j = 0.0;
  std::uint64_t damped_ticks = 0;
};

struct ReplayResult {
  std::vector<std::uint64_t> ticks;  // of the ordinary records replayed, in order
  std::vector<double> positions;
  ForceSeries logged;                // what the log recorded
  ForceSeries own;                   // the log's own configuration, replayed
  std::optional<ForceSeries> other;  // the other configuration (replay --config)
  std::uint64_t compared = 0;        // ticks whose forces were compared (the stepped ones)
  std::uint64_t differing = 0;       // of those, ticks whose forces differ in any bit
  std::optional<std::uint64_t> first_difference;  // its tick
  std::size_t reloads = 0;                        // laws swapped in (reload markers)
  std::size_t rearms = 0;                         // fresh starts after a cleared fault
  // Why the replay ends before the log does ("" when it covers all of it): a gap in the
  // ticks (records dropped or a damaged block skipped), a reload whose configuration the log
  // does not hold.
  std::string stopped;
  // Said when the replay cannot be exact about the passivity observer: the log's driver is not
  // in this build, so its declared delay is unknown and taken as 0 ("" otherwise).
  std::string note;
};

// Loads a configuration recorded in a log (`name` in messages). Throws config::ConfigError.
config::Config config_from_log(const std::string& text, const std::string& name);

// Replays `log` through its own configuration (header, then its config blocks) and, when
// `other` is given, through that one. Throws config::ConfigError when a configuration in the
// log cannot be loaded.
ReplayResult replay_log(const telemetry::LogContents& log, const std::string& log_name,
                        const config::Config* other);

}  // namespace hapticd::service
