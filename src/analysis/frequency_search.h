// Locating the extremum of a real function of frequency on [lo, hi] (theta = omega T, rad):
// a dense uniform grid, extra points where narrow features sit (pole angles), then
// golden-section refinement around the best local maxima. Every frequency-domain check of
// the gate (passivity bound, oscillation margins, DSPR, transparency) goes through here.
#pragma once

#include <functional>
#include <span>

namespace hapticd::analysis {

struct Extremum {
  double value = 0.0;
  double theta = 0.0;  // where it occurs (rad per sample)
};

inline constexpr int kDefaultGrid = 4096;

// Maximum of f on [lo, hi]. Non-finite values of f win (a +inf is returned as found).
Extremum maximize_over_frequency(const std::function<double(double)>& f, double lo, double hi,
                                 std::span<const double> hints = {}, int grid = kDefaultGrid);
// Minimum of f on [lo, hi].
Extremum minimize_over_frequency(const std::function<double(double)>& f, double lo, double hi,
                                 std::span<const double> hints = {}, int grid = kDefaultGrid);

}  // namespace hapticd::analysis
