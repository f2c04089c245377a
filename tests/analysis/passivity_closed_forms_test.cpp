// Every closed form of Roberts, Moore & Colgate that docs/math.md lists, reproduced
// by the numerical bound to a relative 1e-9.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "analysis/passivity.h"
#include "analysis/wall_model.h"

namespace hapticd::analysis {
namespace {

constexpr double kRel = 1e-9;

void expect_rel(double actual, double expected) {
  EXPECT_NEAR(actual, expected, kRel * std::max(1.0, std::abs(expected)))
      << "actual " << actual << " expected " << expected;
}

TransferFunction backward(double k, double b, double t) {
  return environment_filter({k, b, t, WallDiscretization::kBackward});
}
TransferFunction tustin(double k, double b, double t) {
  return environment_filter({k, b, t, WallDiscretization::kTustin});
}

struct Wall {
  double k, b, t;
};
constexpr Wall kWalls[] = {{2000, 0.2, 1e-3}, {1000, 20, 0.02}, {5e4, 3.0, 1e-4}, {300, 0.0, 5e-3}};

TEST(PassivityClosedForm, BackwardDifferenceWallIsKTHalfPlusB) {  // Roberts-Moore-Colgate eq. 46
  for (const Wall& w : kWalls) {
    const PassivityBound pb = passivity_bound(backward(w.k, w.b, w.t), w.t, 0);
    expect_rel(pb.required_damping, w.k * w.t / 2 + w.b);
    EXPECT_TRUE(pb.note.empty());
  }
}

TEST(PassivityClosedForm, BackwardWallWorstFrequencyIsNyquist) {
  const PassivityBound pb = passivity_bound(backward(2000, 0.2, 1e-3), 1e-3, 0);
  EXPECT_NEAR(pb.worst_theta, std::numbers::pi, 1e-6);
  EXPECT_NEAR(pb.worst_frequency_hz, 500.0, 1e-3);
}

TEST(PassivityClosedForm, TustinWallIsKTHalfMinusB) {  // Roberts-Moore-Colgate Example 3
  for (const Wall& w : kWalls) {
    expect_rel(passivity_bound(tustin(w.k, w.b, w.t), w.t, 0).required_damping,
               w.k * w.t / 2 - w.b);
  }
}

TEST(PassivityClosedForm, BackwardDerivativeChainsSumAlphaTwoOverTPowers) {  // eq. 46
  const double t = 2e-3;
  const double alpha[] = {700.0, 0.8, 3e-4, 2e-7};
  TransferFunction h = tf_constant(0.0);
  TransferFunction hn = tf_constant(1.0);  // ((1 - z^-1)/T)^n
  double expected = 0.0;
  for (int n = 0; n < 4; ++n) {
    h = tf_sum(h, tf_scale(hn, alpha[n]));
    expected += alpha[n] * std::pow(2.0 / t, n - 1);
    expect_rel(passivity_bound(h, t, 0).required_damping, expected);
    hn = tf_product(hn, {{1.0 / t, -1.0 / t}, {1.0}});
  }
}

TEST(PassivityClosedForm, FirstOrderIirFilters) {  // Roberts-Moore-Colgate Example 3
  const double t = 1e-3;
  for (double a : {-0.6, -0.2, 0.0, 0.3, 0.8}) {
    // (z - 1)/(z + a) = (1 - z^-1)/(1 + a z^-1)
    const TransferFunction minus{{1.0, -1.0}, {1.0, a}};
    expect_rel(passivity_bound(minus, t, 0).required_damping, t / (1 - a));
    const TransferFunction plus{{-1.0, 1.0}, {1.0, a}};
    expect_rel(passivity_bound(plus, t, 0).required_damping, t / (1 + a));
  }
}

TEST(PassivityClosedForm, OneSampleDelayBothBranches) {  // Roberts-Moore-Colgate Example 4
  const double t = 1e-3;
  // K T >= 4 B: b_req = KT/2 + B + (KT - 2B)
  expect_rel(passivity_bound(backward(5000, 0.2, t), t, 1).required_damping,
             5000 * t / 2 + 0.2 + (5000 * t - 2 * 0.2));
  // K T < 4 B: b_req = KT/2 + B + K^2 T^2 / (8B), worst at cos(wT) = KT/(4B)
  const PassivityBound pb = passivity_bound(backward(1000, 0.5, t), t, 1);
  expect_rel(pb.required_damping, 1000 * t / 2 + 0.5 + 1000.0 * 1000 * t * t / (8 * 0.5));
  EXPECT_NEAR(std::cos(pb.worst_theta), 1000 * t / (4 * 0.5), 1e-6);
}

TEST(PassivityClosedForm, TustinWithOneSampleDelay) {  // Roberts-Moore-Colgate Example 4, Tustin
  const double t = 1e-3;
  for (const auto& [k, b] : {std::pair{1000.0, 0.2}, std::pair{1000.0, 2.0}}) {
    expect_rel(passivity_bound(tustin(k, b, t), t, 1).required_damping,
               k * t / 2 + b + std::abs(k * t - 2 * b));
  }
}

TEST(PassivityClosedForm, DelayedWallMatchesDirichletExpression) {  // Roberts-Moore-Colgate eq. 53
  const double t = 1e-3, k = 3000, b = 0.4;
  for (int n = 2; n <= 3; ++n) {
    double best = -1e300;
    for (int i = 0; i <= 2000000; ++i) {  // brute force of KT/2 D_n(u) - B cos((n+1)u)
      const double u = std::numbers::pi * i / 2000000;
      double dirichlet = 1.0;
      for (int j = 1; j <= n; ++j) dirichlet += 2 * std::cos(j * u);
      best = std::max(best, k * t / 2 * dirichlet - b * std::cos((n + 1) * u));
    }
    EXPECT_NEAR(passivity_bound(backward(k, b, t), t, n).required_damping, best, 1e-9 * best);
  }
}

TEST(PassivityClosedForm, ShortageOfPassivityAddsEta) {  // Roberts-Moore-Colgate eq. 54
  for (double eta : {0.0, 0.05, 1.5}) {
    expect_rel(passivity_bound(backward(2000, 0.2, 1e-3), 1e-3, 0, eta).required_damping,
               1.2 + eta);
  }
}

TEST(PassivityBound, IntegratingWallIsNeverPassive) {
  const TransferFunction integrator{{1.0}, {1.0, -1.0}};
  const PassivityBound pb = passivity_bound(integrator, 1e-3, 0);
  EXPECT_TRUE(std::isinf(pb.required_damping));
  EXPECT_NE(pb.note.find("pole at z = 1"), std::string::npos) << pb.note;
}

TEST(PassivityBound, UnstableWallIsReported) {
  const TransferFunction unstable{{1.0}, {1.0, -1.5}};
  const PassivityBound pb = passivity_bound(unstable, 1e-3, 0);
  EXPECT_TRUE(std::isinf(pb.required_damping));
  EXPECT_NE(pb.note.find("not stable"), std::string::npos) << pb.note;
}

}  // namespace
}  // namespace hapticd::analysis
