// Evaluation of ProfileSpec: held ends, linear segments, right-continuous jumps, sine.
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "config/config.h"
#include "plant_numbers.h"
#include "sim/profile.h"

namespace hapticd::sim {
namespace {

using config::ProfileSpec;
using plant_numbers::kInf;
using plant_numbers::kNaN;

ProfileSpec points(std::vector<config::ProfilePoint> pts) {
  ProfileSpec p;
  p.shape = ProfileSpec::Shape::kPress;
  p.points = std::move(pts);
  return p;
}

TEST(Profile, PiecewiseLinearHoldsRampsAndJumps) {
  const Profile p(points({{1.0, 2.0}, {3.0, 6.0}, {3.0, -1.0}, {4.0, -1.0}}));
  EXPECT_DOUBLE_EQ(p.value(-5.0), 2.0);  // held before the first point
  EXPECT_DOUBLE_EQ(p.slope(0.5), 0.0);
  EXPECT_DOUBLE_EQ(p.value(1.0), 2.0);
  EXPECT_DOUBLE_EQ(p.value(2.0), 4.0);
  EXPECT_DOUBLE_EQ(p.slope(2.0), 2.0);
  EXPECT_DOUBLE_EQ(p.value(std::nextafter(3.0, 0.0)), 6.0);  // just before the jump
  EXPECT_DOUBLE_EQ(p.value(3.0), -1.0);                      // right-continuous
  EXPECT_DOUBLE_EQ(p.slope(3.5), 0.0);
  EXPECT_DOUBLE_EQ(p.value(100.0), -1.0);  // held after the last point
  EXPECT_EQ(p.breakpoints(), (std::vector<double>{1.0, 3.0, 4.0}));
  ASSERT_EQ(p.knots().size(), 3u);
  EXPECT_DOUBLE_EQ(p.knots()[1].value_before, 6.0);
  EXPECT_DOUBLE_EQ(p.knots()[1].value_after, -1.0);
  EXPECT_EQ(p.segment_count(), 4u);
  EXPECT_EQ(p.segment_index(3.0), 2u);
}

TEST(Profile, ConstantAndEmpty) {
  const Profile c(points({{0.0, 0.25}}));
  EXPECT_DOUBLE_EQ(c.value(-1.0), 0.25);
  EXPECT_DOUBLE_EQ(c.value(1.0), 0.25);
  const Profile empty(points({}));
  EXPECT_DOUBLE_EQ(empty.value(3.0), 0.0);
  EXPECT_TRUE(empty.breakpoints().empty());
}

TEST(Profile, Sine) {
  ProfileSpec s;
  s.shape = ProfileSpec::Shape::kSine;
  s.offset = 0.1;
  s.amplitude = 0.02;
  s.frequency_hz = 3.0;
  s.phase_rad = 0.5;
  s.points = {{0.0, 9.0}};  // ignored for a sine
  const Profile p(s);
  const double w = 2 * std::numbers::pi * 3.0;
  for (const double t : {0.0, 0.013, 0.4}) {
    EXPECT_DOUBLE_EQ(p.value(t), 0.1 + 0.02 * std::sin(w * t + 0.5));
    EXPECT_DOUBLE_EQ(p.slope(t), 0.02 * w * std::cos(w * t + 0.5));
  }
  EXPECT_TRUE(p.is_sine());
  EXPECT_TRUE(p.breakpoints().empty());
}

TEST(Profile, RejectsDecreasingTimesAndNonFinite) {
  EXPECT_THROW(Profile(points({{1.0, 0.0}, {0.5, 0.0}})), std::invalid_argument);
  EXPECT_THROW(Profile(points({{kNaN, 0.0}})), std::invalid_argument);
  ProfileSpec s;
  s.shape = ProfileSpec::Shape::kSine;
  s.frequency_hz = kInf;
  EXPECT_THROW(Profile{s}, std::invalid_argument);
}

}  // namespace
}  // namespace hapticd::sim
