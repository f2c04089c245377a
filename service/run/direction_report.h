// What the direction check (control/direction_probe.h) found, as the run reports it: the
// summary's line and object, the event when the wall is armed, and what to change when it
// refuses the device (the driver's own setting that reverses the force, from its registry
// entry).
#pragma once

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "config/config.h"
#include "control/direction_probe.h"
#include "loop/loop_fault.h"
#include "wiring/registry.h"

namespace hapticd::service {

// The sentence after a refusal's cause: the setting that reverses the force (reversed), or
// what lets the check see motion (no motion, never at rest). "" for any other cause.
std::string direction_advice(loop::FaultCause cause, const config::Config& cfg,
                             const wiring::DriverEntry& driver);

// Logs what the check found once it has ended without a refusal (confirmed, or armed
// unchecked under on_no_motion: run).
void announce_direction(const control::ProbeResult& r);

// {"state", "gain", "gain_error", "force", "expected_motion", "ticks", "unchecked"}.
nlohmann::json direction_json(const control::ProbeResult& r);
// The summary's "direction" line; `refused`: the check's verdict ended the run.
void direction_text(const control::ProbeResult& r, bool refused, std::ostream& os);

}  // namespace hapticd::service
