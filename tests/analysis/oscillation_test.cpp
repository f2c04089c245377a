#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/oscillation.h"
#include "analysis/wall_model.h"

namespace hapticd::analysis {
namespace {

TEST(DeviceOperatorZoh, StepResponseEqualsTheContinuousSystemAtSampleInstants) {
  const double m = 0.1, c = 2.0 + 5.0, k = 300.0, t = 1e-3;
  const TransferFunction g = device_operator_zoh(m, 2.0, k, 5.0, t);
  const std::vector<double> step(400, 1.0);
  const std::vector<double> y = simulate(g, step);
  // Underdamped: x(t) = (1/k)(1 - e^{-zw t}(cos wd t + zw/wd sin wd t))
  const double wn = std::sqrt(k / m), zeta = c / (2 * std::sqrt(k * m));
  const double wd = wn * std::sqrt(1 - zeta * zeta), s = zeta * wn;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double tt = static_cast<double>(i) * t;
    const double x = (1 - std::exp(-s * tt) * (std::cos(wd * tt) + s / wd * std::sin(wd * tt))) / k;
    EXPECT_NEAR(y[i], x, 1e-12) << "sample " << i;
  }
}

TransferFunction wall_loop(double k, double b_wall, int delay, double kh) {
  const double t = 1e-3;
  const TransferFunction e = environment_filter({k, b_wall, t, WallDiscretization::kBackward});
  return tf_product(tf_delay(e, delay), device_operator_zoh(0.1, 2.0, kh, 5.0, t));
}

TEST(Oscillation, TsaiColgateHoldsWhereTsypkinFails) {
  // A 1000 N/m wall pressed by a soft (100 N/m) hand: Re L dips below -1 near the
  // hand-wall resonance, but the wedge of Tsai & Colgate (eq. 25) clears -1 at every frequency.
  const OscillationCheck r = oscillation_check(wall_loop(1000, 0.0, 0, 100));
  ASSERT_TRUE(r.applicable) << r.note;
  EXPECT_TRUE(r.tsai_colgate);
  EXPECT_FALSE(r.tsypkin);
  EXPECT_GT(r.tsai_colgate_margin, 0.5);
  EXPECT_LT(r.tsypkin_margin, -0.1);
}

TEST(Oscillation, MarginsAreTheWedgeAndTsypkinExpressions) {
  const TransferFunction l = wall_loop(1000, 0.5, 1, 300);
  const OscillationCheck r = oscillation_check(l);
  ASSERT_TRUE(r.applicable) << r.note;
  double wedge = 1e300, tsy = 1e300;
  for (int i = 1; i <= 200000; ++i) {  // brute force over (0, pi]
    const double th = M_PI * i / 200000;
    const Complex v = frequency_response(l, th);
    const double m = std::sin(th) / (1 - std::cos(th));
    wedge = std::min(wedge, std::max(v.real() + m * v.imag(), v.real() - m * v.imag()) + 1);
    tsy = std::min(tsy, v.real() + 1);
  }
  // The wedge has a kink where Im L changes sign, so a uniform grid can only over-estimate
  // its minimum; the refined search must never be above the grid and be within its step.
  EXPECT_LE(r.tsai_colgate_margin, wedge + 1e-12);
  EXPECT_NEAR(r.tsai_colgate_margin, wedge, 1e-4);
  EXPECT_LE(r.tsypkin_margin, tsy + 1e-12);
  EXPECT_NEAR(r.tsypkin_margin, tsy, 1e-6);
}

TEST(Oscillation, BothHoldForASoftWall) {
  const OscillationCheck r = oscillation_check(wall_loop(100, 0.1, 0, 300));
  ASSERT_TRUE(r.applicable) << r.note;
  EXPECT_TRUE(r.tsai_colgate);
  EXPECT_TRUE(r.tsypkin);
}

TEST(Oscillation, UnstableLinearLoopIsNotApplicable) {
  // A very stiff wall with delay: the loop without the constraint is already unstable,
  // so the criteria (which assume (1 + L)^-1 stable) say nothing.
  const OscillationCheck r = oscillation_check(wall_loop(2e6, 0.0, 3, 300));
  EXPECT_FALSE(r.applicable);
  EXPECT_NE(r.note.find("1/(1 + L) is not stable"), std::string::npos) << r.note;
}

TEST(Oscillation, NegativeDcGainIsNotApplicable) {
  const OscillationCheck r = oscillation_check(tf_constant(-0.5));
  EXPECT_FALSE(r.applicable);
  EXPECT_NE(r.note.find("L(1) < 0"), std::string::npos) << r.note;
}

}  // namespace
}  // namespace hapticd::analysis
