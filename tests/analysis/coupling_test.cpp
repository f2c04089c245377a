// Naghshtabrizi & Hespanha's Example 1: T = 0.02, b = 10, K = 1000, B = 20 and the
// paper's third-order C(z).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "analysis/coupling.h"
#include "analysis/passivity.h"
#include "analysis/wall_model.h"

namespace hapticd::analysis {
namespace {

constexpr double kT = 0.02, kB = 10.0;
const TransferFunction kC{{0.1, -0.0752, 0.0016, -0.0101}, {1, -1.8407, 0.8444, -0.0037}};
const TransferFunction kE = environment_filter({1000, 20, kT, WallDiscretization::kBackward});

TEST(Coupling, Example1SatisfiesTheDsprCondition) {
  const CouplingCheck r = coupling_check(kC, kT, kB);
  EXPECT_TRUE(r.admissible);
  EXPECT_TRUE(r.pole_at_one);
  EXPECT_TRUE(r.dspr) << r.note;
  // Independent evaluation of Re{(z-1)/(Tz)(C(z) - T/(2b))} straight from the formula.
  double lowest = 1e300;
  for (int i = 1; i < 100000; ++i) {
    const double th = std::numbers::pi * i / 100000;
    const Complex z = std::polar(1.0, th);
    const Complex c = frequency_response(kC, th);
    lowest = std::min(lowest, ((z - 1.0) / (kT * z) * (c - kT / (2 * kB))).real());
  }
  EXPECT_NEAR(r.dspr_min_real, lowest, 1e-6);
  EXPECT_GT(r.dspr_min_real, 4.0);
}

TEST(Coupling, WithoutAPoleAtOneDsprFailsAtDc) {
  const CouplingCheck r = coupling_check(tf_constant(0.1), kT, kB);
  EXPECT_TRUE(r.admissible);
  EXPECT_FALSE(r.dspr);
  EXPECT_NEAR(r.dspr_min_real, 0.0, 1e-12);
  EXPECT_NE(r.note.find("no pole at z = 1"), std::string::npos) << r.note;
}

TEST(Coupling, UnstableCouplingIsNotAdmissible) {
  const CouplingCheck r = coupling_check({{0.1}, {1.0, -1.2}}, kT, kB);
  EXPECT_FALSE(r.admissible);
  EXPECT_FALSE(r.dspr);
  EXPECT_NE(r.note.find("outside the unit circle"), std::string::npos) << r.note;
}

TEST(Coupling, ContactMapIsEOverOnePlusEC) {
  const TransferFunction h = contact_map(kE, kC);
  for (double th : {0.01, 0.5, 1.3, 2.9, std::numbers::pi}) {
    const Complex e = frequency_response(kE, th), c = frequency_response(kC, th);
    const Complex expected = e / (1.0 + e * c);
    EXPECT_NEAR(std::abs(frequency_response(h, th) - expected), 0.0, 1e-9 * std::abs(expected));
  }
}

TEST(Coupling, CoupledWallYieldsUnderASteadyPush) {
  EXPECT_EQ(static_stiffness(kE, kC), 0.0);
  EXPECT_DOUBLE_EQ(static_stiffness(kE, std::nullopt), 1000.0);
  // A coupling without an integrator leaves a series spring: K / (1 + K c).
  EXPECT_NEAR(static_stiffness(kE, tf_constant(0.001)), 500.0, 1e-9);
}

TEST(Coupling, TransparencyIsTheWeightedPeakOfHMinusE) {
  const TransferFunction w{{0.1, 0.03}, {100, -99}};  // the paper's W(z) = (0.1z+0.03)/(100z-99)
  const Extremum g = transparency_gamma(contact_map(kE, kC), kE, w);
  // At DC, H(1) = 0 and |W(1) (0 - K)|^2 = (0.13 * 1000)^2; the low-pass W makes DC the peak.
  EXPECT_NEAR(g.value, 16900.0, 1e-6);
  EXPECT_NEAR(g.theta, 0.0, 1e-6);
  // Unit weight: the peak equals a brute-force scan of |H - E|^2.
  const Extremum g1 = transparency_gamma(contact_map(kE, kC), kE, tf_constant(1.0));
  double peak = 0.0;
  for (int i = 0; i <= 200000; ++i) {
    const double th = std::numbers::pi * i / 200000;
    peak = std::max(
        peak, std::norm(frequency_response(contact_map(kE, kC), th) - frequency_response(kE, th)));
  }
  EXPECT_NEAR(g1.value, peak, 1e-6 * peak);
}

TEST(Coupling, BareExample1WallIsNotPassiveButTheCoupledOneIs) {
  EXPECT_NEAR(passivity_bound(kE, kT, 0).required_damping, 30.0, 1e-9);
  EXPECT_LT(passivity_bound(contact_map(kE, kC), kT, 0).required_damping, 1.0);
}

}  // namespace
}  // namespace hapticd::analysis
