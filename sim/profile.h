// A ProfileSpec (hand set-point in m, or operator force in N) in a form that can be evaluated
// at any time and stepped exactly by the plant. Piecewise-linear shapes become knots (distinct
// times; several points at one time make one knot with a jump) and the linear segments between
// them; sine keeps its parameters. Values are right-continuous: at a jump the new value holds.
#pragma once

#include <cstddef>
#include <vector>

#include "config/config.h"

namespace hapticd::sim {

class Profile {
 public:
  // One distinct breakpoint time with the value just before and just after it.
  struct Knot {
    double t_s = 0.0;
    double value_before = 0.0;
    double value_after = 0.0;
  };
  // value(t) = value0 + slope * (t - t0_s) on the segment.
  struct Segment {
    double t0_s = 0.0;
    double value0 = 0.0;
    double slope = 0.0;
  };

  // The zero profile.
  Profile();
  // Throws std::invalid_argument on non-finite numbers or points whose times decrease.
  // A piecewise-linear shape with no points is the zero profile.
  explicit Profile(const config::ProfileSpec& spec);

  bool is_sine() const noexcept { return sine_; }

  // RT-safe: value at t (right-continuous) and its right derivative; no allocation.
  double value(double t_s) const noexcept;
  double slope(double t_s) const noexcept;

  // Piecewise-linear only (empty for sine). Knots are sorted by time.
  const std::vector<Knot>& knots() const noexcept { return knots_; }
  // The distinct breakpoint times, sorted.
  std::vector<double> breakpoints() const;

  // Segment i lies after knot i-1 and before knot i: segment 0 holds the first value, segment
  // knots().size() holds the last. RT-safe.
  std::size_t segment_count() const noexcept { return segments_.size(); }
  const Segment& segment(std::size_t i) const noexcept { return segments_[i]; }
  // Index of the segment in force at t (the number of knots at or before t). RT-safe.
  std::size_t segment_index(double t_s) const noexcept;

  // Sine parameters (zero for piecewise-linear shapes).
  double sine_offset() const noexcept { return offset_; }
  double sine_amplitude() const noexcept { return amplitude_; }
  double sine_omega() const noexcept { return omega_; }  // rad/s
  double sine_phase() const noexcept { return phase_; }

 private:
  bool sine_ = false;
  double offset_ = 0.0;
  double amplitude_ = 0.0;
  double omega_ = 0.0;
  double phase_ = 0.0;
  std::vector<Knot> knots_;
  std::vector<Segment> segments_;  // always knots_.size() + 1 entries
};

}  // namespace hapticd::sim
