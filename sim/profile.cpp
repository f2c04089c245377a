#include "sim/profile.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hapticd::sim {

namespace {

void require_finite(double v, const char* what) {
  if (!std::isfinite(v)) {
    throw std::invalid_argument(std::string("profile: ") + what + " must be finite");
  }
}

}  // namespace

Profile::Profile() : segments_{Segment{}} {}

Profile::Profile(const config::ProfileSpec& spec) {
  if (spec.shape == config::ProfileSpec::Shape::kSine) {
    require_finite(spec.offset, "sine offset");
    require_finite(spec.amplitude, "sine amplitude");
    require_finite(spec.frequency_hz, "sine frequency");
    require_finite(spec.phase_rad, "sine phase");
    sine_ = true;
    offset_ = spec.offset;
    amplitude_ = spec.amplitude;
    omega_ = 2.0 * std::numbers::pi * spec.frequency_hz;
    phase_ = spec.phase_rad;
    segments_.push_back(Segment{});
    return;
  }

  for (std::size_t i = 0; i < spec.points.size(); ++i) {
    const config::ProfilePoint& p = spec.points[i];
    require_finite(p.t_s, "point time");
    require_finite(p.value, "point value");
    if (i > 0 && p.t_s < spec.points[i - 1].t_s) {
      throw std::invalid_argument("profile: point " + std::to_string(i) +
                                  " at t = " + std::to_string(p.t_s) +
                                  " s comes before the previous point; times must not decrease");
    }
    // Equal times merge into one knot: the first value is the left limit, the last the right.
    if (!knots_.empty() && knots_.back().t_s == p.t_s) {
      knots_.back().value_after = p.value;
    } else {
      knots_.push_back(Knot{p.t_s, p.value, p.value});
    }
  }

  if (knots_.empty()) {
    segments_.push_back(Segment{});
    return;
  }
  segments_.reserve(knots_.size() + 1);
  segments_.push_back(Segment{knots_.front().t_s, knots_.front().value_before, 0.0});
  for (std::size_t j = 1; j < knots_.size(); ++j) {
    const Knot& a = knots_[j - 1];
    const Knot& b = knots_[j];
    const double slope = (b.value_before - a.value_after) / (b.t_s - a.t_s);
    require_finite(slope, "slope between points");  // times too close for a double
    segments_.push_back(Segment{a.t_s, a.value_after, slope});
  }
  segments_.push_back(Segment{knots_.back().t_s, knots_.back().value_after, 0.0});
}

std::size_t Profile::segment_index(double t_s) const noexcept {
  const auto it = std::upper_bound(knots_.begin(), knots_.end(), t_s,
                                   [](double t, const Knot& k) { return t < k.t_s; });
  return static_cast<std::size_t>(it - knots_.begin());
}

double Profile::value(double t_s) const noexcept {
  if (sine_) return offset_ + amplitude_ * std::sin(omega_ * t_s + phase_);
  const Segment& s = segments_[segment_index(t_s)];
  return s.value0 + s.slope * (t_s - s.t0_s);
}

double Profile::slope(double t_s) const noexcept {
  if (sine_) return amplitude_ * omega_ * std::cos(omega_ * t_s + phase_);
  return segments_[segment_index(t_s)].slope;
}

std::vector<double> Profile::breakpoints() const {
  std::vector<double> out;
  out.reserve(knots_.size());
  for (const Knot& k : knots_) out.push_back(k.t_s);
  return out;
}

}  // namespace hapticd::sim
