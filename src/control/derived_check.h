// Each key of a configuration is range-checked as it is read, but the numbers the controller
// and the gate derive from several keys (B/T, the normalised coupling, E/(1 + E C), the
// device model's discretisation) can still overflow: a wall of B = 1e306 N s/m makes B/T
// infinite, and an infinite filter coefficient turns the passivity bound into -inf or NaN.
// This check runs once after loading, before anything is analysed or run.
#pragma once

#include "config/config.h"

namespace hapticd::control {

// Not RT-safe. Throws config::ConfigError with one "WHERE: key: what" message per derived
// quantity that is not a finite number, naming the key to change (exit code 2).
void check_derived_quantities(const config::Config& cfg);

}  // namespace hapticd::control
