// The curves `hapticd curves` emits for the plots: the Z-width against the closed forms of
// the passivity bound, and the Nyquist points as the very loop the gate's oscillation check
// judged.
#include "gate/curves.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "gate/gate.h"
#include "gate_configs.h"

namespace hapticd::gate {
namespace {

using test::demo;
using test::example1;

TEST(Zwidth, BackwardDifferenceWithoutDelayIsTheLineKTOver2PlusBEqualsB) {
  const config::Config cfg = demo();
  const std::vector<ZwidthPoint> curve = zwidth_curve(cfg, 0);
  ASSERT_GT(curve.size(), 10u);
  const double t = 1e-3, available = 0.9 * 2.0;
  for (const ZwidthPoint& p : curve) {
    if (p.damping < available) {
      ASSERT_EQ(p.max_stiffness.kind, analysis::StiffnessLimit::Kind::kBounded) << p.damping;
      EXPECT_NEAR(p.max_stiffness.value, 2.0 * (available - p.damping) / t, 1e-6 * 3600)
          << "B = " << p.damping;
    } else {
      EXPECT_EQ(p.max_stiffness.kind, analysis::StiffnessLimit::Kind::kNone) << p.damping;
    }
  }
  EXPECT_EQ(curve.back().max_stiffness.kind, analysis::StiffnessLimit::Kind::kNone);
}

TEST(Zwidth, OneSampleOfDelayFollowsItsClosedForm) {
  const config::Config cfg = demo();
  const double t = 1e-3, available = 1.8;
  for (const ZwidthPoint& p : zwidth_curve(cfg, 1)) {
    if (p.max_stiffness.kind != analysis::StiffnessLimit::Kind::kBounded) continue;
    const double k = p.max_stiffness.value, b = p.damping;
    // b_req = K T/2 + B + (K T - 2B) if K T >= 4B, else K T/2 + B + K^2 T^2 / (8B).
    const double req = k * t >= 4.0 * b ? k * t / 2 + b + (k * t - 2 * b)
                                        : k * t / 2 + b + k * k * t * t / (8 * b);
    EXPECT_NEAR(req, available, 1e-6) << "B = " << b << " K = " << k;
  }
}

TEST(Nyquist, ThePlottedLoopIsTheOneTheGateJudged) {
  const config::Config cfg = demo();
  std::string note;
  const std::vector<NyquistPoint> curve = nyquist_curve(cfg, 0, note);
  ASSERT_EQ(curve.size(), 800u);
  EXPECT_TRUE(note.empty());
  // The Tsai-Colgate margin from the plotted points, as eq. 25 states it.
  double margin = std::numeric_limits<double>::infinity(), tsypkin = margin;
  for (const NyquistPoint& p : curve) {
    const double m = std::sin(p.theta) / (1.0 - std::cos(p.theta));
    margin =
        std::min(margin, std::max(p.l.real() + m * p.l.imag(), p.l.real() - m * p.l.imag()) + 1);
    tsypkin = std::min(tsypkin, p.l.real() + 1.0);
  }
  const GateReport r = evaluate_gate(cfg, 0);
  ASSERT_TRUE(r.oscillation.applicable) << r.oscillation.note;
  // The gate refines its minimum between grid points: the plotted grid can only be above it.
  EXPECT_GE(margin, r.oscillation.tsai_colgate_margin - 1e-9);
  EXPECT_NEAR(margin, r.oscillation.tsai_colgate_margin, 0.02);
  EXPECT_NEAR(tsypkin, r.oscillation.tsypkin_margin, 0.02);
  EXPECT_TRUE(std::is_sorted(curve.begin(), curve.end(),
                             [](auto& a, auto& b) { return a.theta < b.theta; }));
  EXPECT_DOUBLE_EQ(curve.back().theta, M_PI);
}

TEST(Nyquist, BehindACouplingWithAPoleAtOneThereIsNothingToPlotAndItSaysWhy) {
  const config::Config cfg = example1(true);
  std::string note;
  EXPECT_TRUE(nyquist_curve(cfg, 0, note).empty());
  EXPECT_EQ(note, kCouplingPoleNote);
}

}  // namespace
}  // namespace hapticd::gate
