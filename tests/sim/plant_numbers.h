// The simulated plant the sim tests run: sampled at 1 kHz, 0.1 kg, 2 N s/m; and the
// non-finite numbers they feed it.
#pragma once

#include <limits>

namespace hapticd::sim::plant_numbers {

inline constexpr double kT = 1e-3;
inline constexpr double kM = 0.1;
inline constexpr double kB = 2.0;
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace hapticd::sim::plant_numbers
