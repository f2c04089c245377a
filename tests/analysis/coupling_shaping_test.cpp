// The coupling design's second stage against what it must agree with: the reflection
// coefficients against the polynomials they stand for, the convex shaping of the numerator
// against a coupling whose exact gamma is known, and the raised order against the lower one it
// starts from.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/coupling_poles.h"
#include "analysis/coupling_shaping.h"
#include "coupling_example1.h"

namespace hapticd::analysis {
namespace {

TEST(PoleSearch, ReflectionCoefficientsStandForStablePolynomials) {
  // (1 - 0.9 w)(1 + 0.64 w)(1 - 0.6 w + 0.34 w^2): poles 0.9, -0.64, 0.3 +- 0.5j.
  const Polynomial den = poly_mul(poly_mul({1.0, -0.9}, {1.0, 0.64}), Polynomial{1.0, -0.6, 0.34});
  const Polynomial back = polynomial_of(reflection_of(den));
  ASSERT_EQ(back.size(), den.size());
  for (std::size_t i = 0; i < den.size(); ++i) EXPECT_NEAR(back[i], den[i], 1e-12) << i;
  for (const std::vector<double>& kappa :
       {std::vector<double>{3.0, -4.0, 2.5}, std::vector<double>{-6.0, 6.0, -6.0, 0.1}}) {
    for (const Complex& z : poly_roots_z(polynomial_of(kappa))) EXPECT_LT(std::abs(z), 1.0);
  }
}

// An order-3 coupling the exact checks pass (d = 1e-5, D_c = T/(2b)), its gamma and poles.
struct Known {
  CouplingSpec spec = testing::coupling_example1(3);
  TransferFunction c;
  CouplingVerdict v;
  Polynomial poles;  // but z = 1
  Known() {
    const CouplingParameters chi{Eigen::Vector2d(-0.72, -0.25), Eigen::Vector2d(0.01, 0.0)};
    c = coupling_filter_of(coupling_scales(spec), {1e-5, 0.001}, chi);
    v = evaluate_coupling(spec, c);
    poles = poly_deflate(c.den, 1.0);
  }
};

// At the known coupling's poles, the shaping reaches its gamma (it is one of the numerators
// searched) and finds a numerator at least as good, which the exact checks pass; far below
// what it found, the disks cannot be met.
TEST(CouplingShaper, AtACouplingsPolesDoesAtLeastAsWellAsIt) {
  const Known k;
  ASSERT_TRUE(k.v.valid()) << k.v.note;
  const auto solver = make_sdp_solver();
  CouplingShaper shaper(k.spec, *solver, k.c);
  EXPECT_LE(shaper.slack(k.poles, 1.02 * k.v.gamma), 0.0);
  const std::optional<ShapedCoupling> s = shaper.best(k.poles, 0.5 * k.v.gamma, k.v.gamma, 1e-3);
  ASSERT_TRUE(s.has_value());
  EXPECT_TRUE(evaluate_coupling(k.spec, s->coupling).valid());
  EXPECT_LE(s->verdict.gamma, k.v.gamma);
  EXPECT_GT(shaper.slack(k.poles, 0.9 * s->verdict.gamma), 0.0);
}

// From the family d z/(z-1) + D_c alone (order 1) to order 2: the search keeps what it had (a
// pole at z = 0 leaves the lower order's numerator in reach), reports a step per sweep and
// converges within its budget; a budget of one step is not convergence.
TEST(PoleSearch, RaisingTheOrderKeepsWhatTheLowerOrderHad) {
  CouplingSpec spec = testing::coupling_example1(1);
  const double d = 3e-5, dc = 0.001;
  const TransferFunction family{{d + dc, -dc}, {1.0, -1.0}};
  const ShapedCoupling seed{family, evaluate_coupling(spec, family)};
  ASSERT_TRUE(seed.verdict.valid()) << seed.verdict.note;
  spec.order = 2;
  const auto solver = make_sdp_solver();
  int reported = 0, at_order2 = 0;
  const PoleSearchResult r = search_poles(spec, seed, *solver, {}, [&](const PoleSearchStep& s) {
    EXPECT_EQ(s.index, ++reported);
    EXPECT_LE(s.best, seed.verdict.gamma);
    at_order2 += s.order == 2;
  });
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(reported, r.steps);
  EXPECT_GT(at_order2, 0);
  EXPECT_TRUE(evaluate_coupling(spec, r.best.coupling).valid());
  EXPECT_LT(r.best.verdict.gamma, seed.verdict.gamma);
  PoleSearchOptions one;
  one.max_steps = 1;
  EXPECT_FALSE(search_poles(spec, seed, *solver, one).converged);
}

}  // namespace
}  // namespace hapticd::analysis
