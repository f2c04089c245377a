// The passivity observer's bookkeeping against hand-computed energies, and its controller's
// damping: what it adds, when, in which direction and how much at most.
#include "control/passivity_observer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace hapticd::control {
namespace {

constexpr double kPeriod = 0.001;

ObserverParams params(config::PassivityControl mode, double b, int delay = 0,
                      double max_damping = 50.0) {
  ObserverParams p;
  p.mode = mode;
  p.device_damping = b;
  p.sample_period = kPeriod;
  p.device_delay = delay;
  p.max_damping = max_damping;
  return p;
}

// A law with this saturation (and no no_pull) for damp().
ControlLaw law(double max_force) {
  ControlLaw l;
  l.max_force = max_force;
  return l;
}

// A tick that writes `u` whatever the controller would add.
void write(PassivityObserver& o, double x, double u) {
  o.observe(x, true, 1);
  o.commanded(u, 0.0);
}

// One tick as the loop runs it: observe, (damp), write.
double tick(PassivityObserver& o, double x, double wall, bool fresh = true,
            std::uint32_t periods = 1) {
  o.observe(x, fresh, periods);
  const Damping d = o.damp(wall, law(100.0));
  o.commanded(d.command, d.added);
  return d.command;
}

TEST(PassivityObserver, CreditsTheDampingAndChargesTheHeldForceExactly) {
  PassivityObserver o(params(config::PassivityControl::kObserve, 2.0));
  tick(o, 0.0, 3.0);     // u = 3 N held over the first period
  tick(o, 0.001, -1.0);  // moved 1 mm under 3 N: the force did 3 mJ of work on the device
  const double e1 = 2.0 * 0.001 * 0.001 / kPeriod - 3.0 * 0.001;
  EXPECT_DOUBLE_EQ(o.energy_j(), e1);
  EXPECT_DOUBLE_EQ(o.wall_work_j(), 3.0 * 0.001);
  tick(o, 0.0005, 0.0);  // back 0.5 mm under -1 N: 0.5 mJ more done on the device
  EXPECT_DOUBLE_EQ(o.energy_j(), e1 + 2.0 * 0.0005 * 0.0005 / kPeriod - 0.0005);
  EXPECT_DOUBLE_EQ(o.min_energy_j(), std::min(0.0, o.energy_j()));
  EXPECT_EQ(o.negative_ticks(), o.energy_j() < 0.0 ? 2u : 0u);
}

TEST(PassivityObserver, TheForceActingIsTheOneWrittenTheDeviceDelayEarlier) {
  PassivityObserver o(params(config::PassivityControl::kObserve, 0.0, 2));
  tick(o, 0.0, 5.0);    // written at tick 0: acts over the period from tick 2 to 3
  tick(o, 0.001, 7.0);  // the period 0-1: nothing written two ticks before it (0 N)
  tick(o, 0.002, 9.0);  // the period 1-2: still nothing
  EXPECT_DOUBLE_EQ(o.wall_work_j(), 0.0);
  tick(o, 0.003, 0.0);  // the period 2-3: the 5 N
  EXPECT_DOUBLE_EQ(o.wall_work_j(), 5.0 * 0.001);
  tick(o, 0.004, 0.0);  // then the 7 N
  EXPECT_DOUBLE_EQ(o.wall_work_j(), 12.0 * 0.001);
  EXPECT_DOUBLE_EQ(o.energy_j(), -12.0 * 0.001);
}

TEST(PassivityObserver, MotionAcrossStaleTicksIsSpreadOverThePeriodsItSpans) {
  PassivityObserver o(params(config::PassivityControl::kObserve, 4.0));
  tick(o, 0.0, 2.0);
  tick(o, 0.0, 6.0, false);  // stale: the held position, the motion shows later
  EXPECT_DOUBLE_EQ(o.energy_j(), 0.0);
  tick(o, 0.003, 0.0, true, 2);  // 3 mm over 1 + 2 periods under 2, 6 and 6 N
  const double dx = 0.003, n = 3.0, mean_force = (2.0 + 6.0 + 6.0) / 3.0;
  EXPECT_DOUBLE_EQ(o.wall_work_j(), mean_force * dx);
  // b dx^2 / (n T): the least b can dissipate when the motion takes three periods.
  EXPECT_DOUBLE_EQ(o.energy_j(), 4.0 * dx * dx / (n * kPeriod) - mean_force * dx);
}

TEST(PassivityObserver, OffObservesNoEnergyButStillCountsTheWallsWork) {
  PassivityObserver o(params(config::PassivityControl::kOff, 2.0));
  tick(o, 0.0, 3.0);
  tick(o, 0.001, 0.0);
  EXPECT_FALSE(o.enabled());
  EXPECT_EQ(o.energy_j(), 0.0);
  EXPECT_DOUBLE_EQ(o.wall_work_j(), 0.003);
}

TEST(PassivityObserver, ObserveNeverChangesTheCommand) {
  PassivityObserver o(params(config::PassivityControl::kObserve, 0.0));
  tick(o, 0.0, 10.0);
  EXPECT_EQ(tick(o, 0.001, 4.0), 4.0);  // energy -10 mJ, and still the wall's 4 N
  EXPECT_LT(o.energy_j(), 0.0);
  EXPECT_EQ(o.damped_ticks(), 0u);
}

TEST(PassivityObserver, DampAddsTheDampingThatDissipatesTheDeficitAgainstTheMotion) {
  PassivityObserver o(params(config::PassivityControl::kDamp, 0.0, 0, 1e6));
  EXPECT_EQ(tick(o, 0.0, 10.0), 10.0);  // nothing observed yet: the wall's force
  write(o, 0.001, 10.0);                // E = -10 mJ, v = +1 m/s
  o.observe(0.002, true, 1);            // E = -20 mJ, v still +1 m/s
  const double e = o.energy_j();
  ASSERT_DOUBLE_EQ(e, -0.02);
  const Damping d = o.damp(4.0, law(100.0));
  const double alpha = -e / (1.0 * 1.0 * kPeriod);  // alpha v^2 T = -E
  EXPECT_DOUBLE_EQ(d.alpha, alpha);
  EXPECT_DOUBLE_EQ(d.command, 4.0 - alpha * 1.0);  // against the motion (+x)
  EXPECT_DOUBLE_EQ(d.added, d.command - 4.0);
  EXPECT_FALSE(d.saturated);
  EXPECT_EQ(o.damped_ticks(), 1u);
}

TEST(PassivityObserver, DampIsBoundedAndSaturatedToTheLawsMaximum) {
  PassivityObserver o(params(config::PassivityControl::kDamp, 0.0, 0, 3.0));
  tick(o, 0.0, 10.0);
  o.observe(0.001, true, 1);  // E = -10 mJ at 1 m/s would ask for 10 N s/m
  Damping d = o.damp(0.0, law(100.0));
  EXPECT_DOUBLE_EQ(d.alpha, 3.0);
  EXPECT_DOUBLE_EQ(d.command, -3.0);
  d = o.damp(-9.0, law(10.0));  // -9 - 3 is beyond the law's 10 N
  EXPECT_EQ(d.command, -10.0);
  EXPECT_TRUE(d.saturated);
  EXPECT_DOUBLE_EQ(o.max_alpha(), 3.0);
}

TEST(PassivityObserver, AReversedMotionIsExpectedToReverseAgain) {
  PassivityObserver o(params(config::PassivityControl::kDamp, 0.0, 0, 1e6));
  write(o, 0.0, 10.0);
  write(o, 0.001, -10.0);   // +1 m/s under +10 N: E = -10 mJ
  o.observe(0.0, true, 1);  // then -1 m/s under -10 N: E = -20 mJ, the motion reversed
  ASSERT_DOUBLE_EQ(o.energy_j(), -0.02);
  const Damping d = o.damp(0.0, law(1e9));
  // Held over the coming period, where the motion is expected at +1 m/s again: against +x.
  EXPECT_LT(d.command, 0.0);
  // A damper on the last velocity (-1 m/s) would have pushed +x: along the expected motion.
}

TEST(PassivityObserver, NoDampingWhilePassiveOrAtRest) {
  PassivityObserver o(params(config::PassivityControl::kDamp, 2.0));
  tick(o, 0.0, -1.0);
  EXPECT_EQ(tick(o, 0.001, 5.0), 5.0);  // the force took energy out: E > 0
  EXPECT_GT(o.energy_j(), 0.0);
  PassivityObserver at_rest(params(config::PassivityControl::kDamp, 0.0));
  tick(at_rest, 0.0, 1.0);
  tick(at_rest, 0.001, 1.0);
  at_rest.observe(0.001, true, 1);  // E < 0 but no motion: nothing to damp
  EXPECT_EQ(at_rest.damp(2.0, law(10.0)).command, 2.0);
}

TEST(PassivityObserver, RestartKeepsTheEnergyAndForgetsTheForceInFlight) {
  PassivityObserver o(params(config::PassivityControl::kObserve, 0.0, 1));
  tick(o, 0.0, 4.0);
  tick(o, 0.001, 4.0);
  tick(o, 0.002, 0.0);
  const double e = o.energy_j();
  o.restart();
  tick(o, 0.5, 0.0);    // a new run's first sample: no period to account
  tick(o, 0.501, 0.0);  // the 4 N in flight before the restart never acts
  EXPECT_EQ(o.energy_j(), e);
}

TEST(PassivityObserver, HoldsAnyDelayTheDriverDeclares) {
  // A slow HID poll declares hundreds of samples: the history is sized for it.
  PassivityObserver o(params(config::PassivityControl::kObserve, 0.0, 300));
  tick(o, 0.0, 7.0);
  for (int k = 1; k <= 300; ++k) tick(o, 0.0, 0.0);
  EXPECT_EQ(o.wall_work_j(), 0.0);
  tick(o, 0.001, 0.0);  // the 7 N written 301 ticks ago acts over this period
  EXPECT_DOUBLE_EQ(o.wall_work_j(), 0.007);
  EXPECT_THROW(PassivityObserver(params(config::PassivityControl::kObserve, 1.0, -1)),
               std::invalid_argument);
  ObserverParams p = params(config::PassivityControl::kObserve, 1.0);
  p.sample_period = 0.0;
  EXPECT_THROW(PassivityObserver{p}, std::invalid_argument);
}

TEST(PassivityObserver, TheGovernorStopsAControllerWhoseForcesPutEnergyIn) {
  PassivityObserver o(params(config::PassivityControl::kDamp, 0.0, 0, 1e6));
  write(o, 0.0, 10.0);
  write(o, 0.001, 10.0);  // E = -10 mJ at +1 m/s
  const Damping first = o.damp(0.0, law(1e9));
  ASSERT_LT(first.command, 0.0);  // against the expected +x motion
  o.commanded(first.command, first.added);
  o.observe(0.0, true, 1);  // but the device went -x: that force pushed along the motion
  EXPECT_LT(o.damping_work_j(), 0.0);
  ASSERT_LT(o.energy_j(), 0.0);
  EXPECT_EQ(o.damp(0.0, law(1e9)).command, 0.0) << "stopped for the rest of this deficit";
  EXPECT_EQ(o.damped_ticks(), 1u);
}

TEST(PassivityObserver, UnderNoPullTheControllerNeverPulls) {
  PassivityObserver o(params(config::PassivityControl::kDamp, 0.0, 0, 1e6));
  write(o, 0.0, 10.0);
  o.observe(0.001, true, 1);  // E < 0 at +1 m/s: the damping force points -x
  ControlLaw l = law(100.0);
  l.no_pull = true;
  l.normal = -1.0;  // the wall occupies x < x0: a force toward -x pulls into it
  const Damping d = o.damp(0.0, l);
  EXPECT_EQ(d.command, 0.0);
  EXPECT_EQ(d.alpha, 0.0);
  l.normal = 1.0;  // now -x pushes out of the wall: allowed
  EXPECT_LT(o.damp(0.0, l).command, 0.0);
}

TEST(PassivityObserver, TheControllersBoundIsTheSmallerOfTheSettingAndNineTenthsOf2mOverT) {
  config::Config cfg;
  cfg.device.mass = 0.1;
  cfg.loop.rate_hz = 50.0;
  cfg.safety.passivity_max_damping = 100.0;
  EXPECT_DOUBLE_EQ(observer_params(cfg, 0).max_damping, 0.9 * 2.0 * 0.1 / 0.02);
  cfg.safety.passivity_max_damping = 3.0;
  EXPECT_DOUBLE_EQ(observer_params(cfg, 0).max_damping, 3.0);
}

TEST(PassivityObserver, ThePeriodIsTheLoopsWholeNanoseconds) {
  config::Config cfg;
  cfg.loop.rate_hz = 1024.0;  // 976562.5 ns: the loop runs 976563
  EXPECT_EQ(observer_params(cfg, 0).sample_period, 976563e-9);
}

}  // namespace
}  // namespace hapticd::control
