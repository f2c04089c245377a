// The coupled wall: the algebraic loop against an independent solver, and in contact the
// closed loop against E / (1 + E C) from the analysis library (same numbers, two code paths).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/wall_model.h"
#include "control/controller.h"

namespace hapticd::control {
namespace {

const std::vector<double> kCn{0.1, -0.0752, 0.0016, -0.0101};
const std::vector<double> kCd{1, -1.8407, 0.8444, -0.0037};

config::Config coupled(config::Discretization disc) {
  config::Config c;
  c.loop.rate_hz = 50.0;  // Naghshtabrizi & Hespanha's Example 1: T = 0.02
  c.wall.stiffness = 1000;
  c.wall.damping = 20;
  c.wall.discretization = disc;
  c.wall.coupling = {true, kCn, kCd};
  c.device.max_force = 1e12;
  return c;
}

// offset + speed * k plus a wiggle at two frequencies (positions in m, k in samples).
std::vector<double> test_positions(std::size_t n, double offset, double speed) {
  std::vector<double> x(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k);
    x[k] = offset + speed * t + 0.004 * std::sin(0.37 * t) + 0.002 * std::cos(1.9 * t + 0.3);
  }
  return x;
}

TEST(ControllerCoupling, InContactTheLoopIsEOverOnePlusEC) {
  for (auto disc : {config::Discretization::kBackward, config::Discretization::kTustin}) {
    const config::Config cfg = coupled(disc);
    ControlLaw law = make_control_law(cfg);
    law.require_outside_start = false;  // starts in contact on purpose
    Controller ctl(law);
    const auto e = analysis::environment_filter({1000, 20, 0.02,
                                                 disc == config::Discretization::kTustin
                                                     ? analysis::WallDiscretization::kTustin
                                                     : analysis::WallDiscretization::kBackward});
    const auto h = analysis::contact_map(e, analysis::TransferFunction{kCn, kCd});
    // C has a pole at z = 1, so the coupled wall yields under a constant push (H(1) = 0) and
    // its proxy drifts back to the surface. Pushing in steadily keeps it in contact, where
    // the wall is linear and f = H p.
    const std::vector<double> x = test_positions(400, 0.05, 0.01);
    const std::vector<double> expected = analysis::simulate(h, x);
    for (std::size_t k = 0; k < x.size(); ++k) {
      const ControlOutput o = ctl.step(x[k]);
      ASSERT_TRUE(o.flags & kControlContact) << "k=" << k;
      EXPECT_NEAR(o.force_computed, expected[k], 1e-9 * (1 + std::abs(expected[k]))) << "k=" << k;
    }
  }
}

// Reference: keep whole histories and solve f = e0 max(q - c0 f, 0) + r by bisection
// (the left side minus the right is strictly increasing in f).
class ReferenceCoupledWall {
 public:
  double step(double p) {
    const double t = 0.02, k = 1000, b = 20;
    const double e0 = k + b / t, e1 = -b / t;
    double c_past = 0.0;
    const std::size_t n = f_.size();
    for (std::size_t i = 1; i < kCn.size() && i <= n; ++i) c_past += kCn[i] * f_[n - i];
    for (std::size_t i = 1; i < kCd.size() && i <= n; ++i) c_past -= kCd[i] * c_[n - i];
    const double q = p - c_past;
    const double r = n > 0 ? e1 * xi_[n - 1] : 0.0;
    const double c0 = kCn[0];
    double lo = -1e9, hi = 1e9;
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (mid - e0 * std::max(q - c0 * mid, 0.0) - r > 0 ? hi : lo) = mid;
    }
    const double f = 0.5 * (lo + hi);
    xi_.push_back(std::max(q - c0 * f, 0.0));
    f_.push_back(f);
    c_.push_back(c0 * f + c_past);
    return f;
  }

 private:
  std::vector<double> xi_, f_, c_;
};

TEST(ControllerCoupling, AlgebraicLoopMatchesAnIndependentSolverInAndOutOfContact) {
  ControlLaw law = make_control_law(coupled(config::Discretization::kBackward));
  law.require_outside_start = false;  // the reference solver has no start-up arming
  Controller ctl(law);
  ReferenceCoupledWall ref;
  // Around the wall: the proxy enters and leaves contact many times.
  const std::vector<double> x = test_positions(600, 0.001, 0.0);
  int transitions = 0;
  bool was_in = false;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const ControlOutput o = ctl.step(x[k]);
    const double f = ref.step(x[k]);
    EXPECT_NEAR(o.force_computed, f, 1e-6 * (1 + std::abs(f))) << "k=" << k;
    const bool in = o.flags & kControlContact;
    transitions += in != was_in;
    was_in = in;
  }
  EXPECT_GT(transitions, 10);  // the test really exercised both branches
}

}  // namespace
}  // namespace hapticd::control
