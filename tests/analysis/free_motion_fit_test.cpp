// The identification fit against data from an independent model of the device: the continuous
// m dv/dt = -b v + u - c sign(v) integrated in fine steps under the held force, sampled every
// T, with or without encoder quantisation, delay and friction.
#include "analysis/free_motion_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace hapticd::analysis {
namespace {

struct Device {
  double mass = 0.1, damping = 2.0, coulomb = 0.0;
  int delay = 0;
  double counts_per_m = 0.0;  // 0: an ideal encoder
};

FreeMotionData simulate(const Device& dev, const std::vector<double>& u, double period,
                        int declared_delay) {
  FreeMotionData d;
  d.sample_period = period;
  d.force = u;
  d.delay = declared_delay;
  constexpr int kSub = 400;
  const double h = period / kSub;
  double x = -0.02, v = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double q =
        dev.counts_per_m > 0.0 ? std::floor(x * dev.counts_per_m) / dev.counts_per_m : x;
    d.position.push_back(q);
    d.valid.push_back(true);
    const double f = k >= static_cast<std::size_t>(dev.delay) ? u[k - dev.delay] : 0.0;
    for (int i = 0; i < kSub; ++i) {  // midpoint steps: second-order accurate
      const auto accel = [&](double vel) {
        const double fr = vel > 0.0 ? -dev.coulomb : vel < 0.0 ? dev.coulomb : 0.0;
        return (f - dev.damping * vel + fr) / dev.mass;
      };
      const double vm = v + 0.5 * h * accel(v);
      x += h * vm;
      v += h * accel(vm);
    }
  }
  return d;
}

const double kPeriod = 1e-3;
std::vector<double> excitation(double amplitude = 4.0) {
  return multisine(amplitude, 3.0, 60.0, 6.0, kPeriod);
}

TEST(FreeMotionFit, RecoversMassAndDampingOfAnIdealEncoder) {
  const FreeMotionFit f = fit_free_motion(simulate({0.1, 2.0}, excitation(), kPeriod, 0));
  EXPECT_NEAR(f.mass.value, 0.1, 1e-4);
  EXPECT_NEAR(f.damping.value, 2.0, 2e-3);
  EXPECT_FALSE(f.coulomb_kept);
  EXPECT_EQ(f.delay, 0);
  EXPECT_EQ(f.samples, 6000u);
  EXPECT_LT(f.rms_residual, 1e-6);
}

TEST(FreeMotionFit, WithinOnePercentThroughAQuantisingEncoderAndItsIntervalHoldsTheTruth) {
  for (const Device dev : {Device{0.1, 2.0}, Device{0.35, 0.8}, Device{0.05, 6.0}}) {
    Device q = dev;
    q.counts_per_m = 1e5;  // 10 um counts
    const FreeMotionFit f = fit_free_motion(simulate(q, excitation(), kPeriod, 0));
    EXPECT_NEAR(f.mass.value, dev.mass, 0.01 * dev.mass) << dev.mass << " " << dev.damping;
    EXPECT_NEAR(f.damping.value, dev.damping, 0.01 * dev.damping) << dev.mass << " " << dev.damping;
    EXPECT_GT(f.mass.ci95, 0.0);
    EXPECT_LT(f.mass.ci95, 0.01 * dev.mass);
    EXPECT_LT(f.rms_residual, 1e-5);  // about a count's uniform error: 2.9 um
  }
}

TEST(FreeMotionFit, FindsTheDelayWhenTheDeclaredOneIsWrong) {
  Device dev;
  dev.delay = 2;
  const FreeMotionFit f = fit_free_motion(simulate(dev, excitation(), kPeriod, 1));
  EXPECT_EQ(f.delay, 2);
  EXPECT_NEAR(f.mass.value, 0.1, 1e-3);
  EXPECT_NEAR(f.damping.value, 2.0, 0.02);
}

TEST(FreeMotionFit, KeepsCoulombFrictionOnlyWhenThereIsSome) {
  Device dev;
  dev.coulomb = 0.3;
  const FreeMotionFit f = fit_free_motion(simulate(dev, excitation(), kPeriod, 0));
  ASSERT_TRUE(f.coulomb_kept);
  EXPECT_NEAR(f.coulomb.value, 0.3, 0.05);
  EXPECT_NEAR(f.damping.value, 2.0, 0.1);
  EXPECT_NEAR(f.mass.value, 0.1, 0.005);
  const FreeMotionFit none =
      fit_free_motion(simulate({0.1, 2.0, 0.0, 0, 1e5}, excitation(), kPeriod, 0));
  EXPECT_FALSE(none.coulomb_kept);
  EXPECT_EQ(none.coulomb.value, 0.0);
}

TEST(FreeMotionFit, LeavesOutSamplesThatWereNotFresh) {
  FreeMotionData d = simulate({0.1, 2.0}, excitation(), kPeriod, 0);
  for (std::size_t k = 100; k < d.position.size(); k += 7) {
    d.valid[k] = false;
    d.position[k] = 1e3;  // garbage where nothing was read: must not be fitted
  }
  const FreeMotionFit f = fit_free_motion(d);
  EXPECT_NEAR(f.mass.value, 0.1, 1e-4);
  EXPECT_NEAR(f.damping.value, 2.0, 2e-3);
  EXPECT_LT(f.samples, 6000u);
}

// Issue 32: the force's sign flipped fits a negative mass and damping: the fit says the force is
// reversed, with the device's own m and b.
TEST(FreeMotionFit, AReversedForceFitsANegativeDeviceAndSaysSo) {
  FreeMotionData d = simulate({0.1, 2.0}, excitation(), kPeriod, 0);
  EXPECT_FALSE(fit_free_motion(d).force_reversed);
  FreeMotionData reversed = d;
  for (double& u : reversed.force) u = -u;
  const FreeMotionFit f = fit_free_motion(reversed);
  EXPECT_TRUE(f.force_reversed);
  EXPECT_NEAR(f.mass.value, 0.1, 1e-4);
  EXPECT_NEAR(f.damping.value, 2.0, 2e-3);
  EXPECT_LT(f.mass.ci95, 1e-3);
}

TEST(FreeMotionFit, RefusesDataThatIsNoFreeDevice) {
  FreeMotionData d = simulate({0.1, 2.0}, excitation(), kPeriod, 0);
  FreeMotionData held = d;  // held still: nothing moved
  for (double& x : held.position) x = 0.01;
  EXPECT_THROW(fit_free_motion(held), std::invalid_argument);
  FreeMotionData silent = d;
  for (double& u : silent.force) u = 0.0;
  EXPECT_THROW(fit_free_motion(silent), std::invalid_argument);
  FreeMotionData short_one = d;
  short_one.force.resize(20);
  short_one.position.resize(20);
  short_one.valid.resize(20);
  EXPECT_THROW(fit_free_motion(short_one), std::invalid_argument);
  d.position.pop_back();
  EXPECT_THROW(fit_free_motion(d), std::invalid_argument);
}

TEST(Multisine, PeaksAtTheAmplitudeAndFadesInAndOut) {
  const std::vector<double> u = multisine(3.0, 2.0, 50.0, 4.0, kPeriod);
  ASSERT_EQ(u.size(), 4000u);
  double peak = 0.0;
  for (const double v : u) peak = std::max(peak, std::abs(v));
  EXPECT_NEAR(peak, 3.0, 1e-12);
  EXPECT_EQ(u.front(), 0.0);
  EXPECT_LT(std::abs(u.back()), 1e-3);
  EXPECT_THROW(multisine(1.0, 2.0, 600.0, 4.0, kPeriod), std::invalid_argument);  // above Nyquist
  EXPECT_THROW(multisine(1.0, 0.1, 50.0, 4.0, kPeriod), std::invalid_argument);   // < 1 cycle
  EXPECT_THROW(multisine(1.0, 50.0, 20.0, 4.0, kPeriod), std::invalid_argument);  // empty band
}

}  // namespace
}  // namespace hapticd::analysis
