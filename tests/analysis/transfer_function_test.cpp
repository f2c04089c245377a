#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "analysis/transfer_function.h"

namespace hapticd::analysis {
namespace {

TEST(TransferFunction, PolesAreInTheZPlane) {
  // 1 / (1 - 0.5 z^-1) has its pole at z = 0.5; a pure delay z^-2 has none.
  const auto p = poles({{1.0}, {1.0, -0.5}});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NEAR(p[0].real(), 0.5, 1e-12);
  EXPECT_TRUE(poles({{0.0, 0.0, 1.0}, {1.0}}).empty());
  EXPECT_TRUE(is_stable({{1.0}, {1.0, -0.5}}));
  EXPECT_FALSE(is_stable({{1.0}, {1.0, -1.0}}));
}

TEST(TransferFunction, FrequencyResponseUsesZEqualsEToTheJTheta) {
  // z^-1 at theta: e^{-j theta}
  const Complex v = frequency_response({{0.0, 1.0}, {1.0}}, 0.3);
  EXPECT_NEAR(v.real(), std::cos(0.3), 1e-15);
  EXPECT_NEAR(v.imag(), -std::sin(0.3), 1e-15);
}

TEST(TransferFunction, SimulateIsTheDifferenceEquation) {
  // y_k = 0.5 y_{k-1} + u_k: impulse response 0.5^k
  const std::vector<double> u{1, 0, 0, 0};
  const auto y = simulate({{1.0}, {1.0, -0.5}}, u);
  EXPECT_EQ(y, (std::vector<double>{1, 0.5, 0.25, 0.125}));
}

TEST(TransferFunction, DcGainResolvesAZeroMeetingAPoleAtOne) {
  EXPECT_DOUBLE_EQ(dc_gain({{1.0, -1.0}, {1.0, -1.0}}), 1.0);
  EXPECT_TRUE(std::isinf(dc_gain({{1.0}, {1.0, -1.0}})));
  EXPECT_DOUBLE_EQ(dc_gain({{2.0, 1.0}, {1.0, 0.5}}), 2.0);
}

TEST(TransferFunction, FeedbackClosesTheLoop) {
  // K / (1 + K c) for constants
  const TransferFunction h = tf_feedback(tf_constant(4.0), tf_constant(0.25));
  EXPECT_DOUBLE_EQ(dc_gain(h), 2.0);
}

}  // namespace
}  // namespace hapticd::analysis
