// A client's commanded force (loop/client_force.h) on its own: the newest offer each tick, held
// then faded when its client falls silent, off while its observer's energy is spent, nothing
// non-finite ever out, nothing allocated.
#include "loop/client_force.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "alloc_counter.h"

namespace hapticd::loop {
namespace {

using kinematics::Vec3;
constexpr std::int64_t kMs = 1000000;

ClientForceLimits limits() { return {2.0, 100 * kMs, 50 * kMs, 0.5, 0.001}; }

TEST(ClientForce, HeldThenFadedToZeroOverTheRampWhenItsClientFallsSilent) {
  ClientForce f(limits());
  EXPECT_EQ(f.step(0), Vec3::Zero());
  f.offer(Vec3(1.0, 0.0, 0.0), 10 * kMs);
  EXPECT_EQ(f.step(10 * kMs), Vec3(1.0, 0.0, 0.0));
  EXPECT_EQ(f.step(110 * kMs), Vec3(1.0, 0.0, 0.0));  // held for 100 ms
  EXPECT_NEAR(f.step(135 * kMs).x(), 0.5, 1e-12);     // half way down the 50 ms ramp
  EXPECT_EQ(f.step(160 * kMs), Vec3::Zero());         // gone at 150 ms
  f.offer(Vec3(0.0, -2.0, 0.0), 200 * kMs);           // sending again: full at once
  EXPECT_EQ(f.step(201 * kMs), Vec3(0.0, -2.0, 0.0));
  f.offer(Vec3(std::nan(""), 0.0, 0.0), 202 * kMs);  // never out: zero instead
  EXPECT_EQ(f.step(203 * kMs), Vec3::Zero());
}

// Pushing a device that gives way at 2 m/s along the force: 1 N does 2 mJ a tick, the observer
// refills 0.5 mJ: the 0.5 J are spent in about a third of a second, and then the force is off
// while the device moves on under it; what it did in all stays within E (1 + t).
TEST(ClientForce, OffOnceItHasPutItsEnergyIntoTheDevice) {
  ClientForce f(limits());
  f.offer(Vec3(1.0, 0.0, 0.0), 0);
  double x = 0.0, work = 0.0;
  int on = 0;
  Vec3 last = Vec3::Zero();
  for (int k = 0; k < 1000; ++k) {
    const Vec3 out = f.step(k * kMs / 10);  // within the hold throughout
    x += 0.002;
    work += last.x() * 0.002;
    f.acted(out, Vec3(x, 0.0, 0.0), true);
    last = out;
    on += out.x() > 0.0 ? 1 : 0;
  }
  // E (1 + t), and the one tick's work that takes the energy below zero.
  EXPECT_LE(work, 0.5 * (1.0 + 1.0) + 0.002 + 1e-9);
  EXPECT_LT(on, 700) << "the force stayed on as it pushed energy in";
  EXPECT_GT(on, 300);
  // Held still, it does no work: on for good.
  for (int k = 0; k < 100; ++k) f.acted(f.step(0), Vec3(x, 0.0, 0.0), true);
  EXPECT_EQ(f.step(0), Vec3(1.0, 0.0, 0.0));
  EXPECT_FALSE(f.limited());
}

TEST(ClientForce, ARunStartsWithoutTheLastRunsForceAndAllocatesNothing) {
  ClientForce f(limits());
  f.offer(Vec3(1.0, 1.0, 0.0), 0);
  EXPECT_NE(f.step(0), Vec3::Zero());
  f.restart();
  EXPECT_EQ(f.step(0), Vec3::Zero()) << "a re-arming kept the force of before the fault";
  testing::AllocationScope scope;
  for (int k = 0; k < 1000; ++k) f.acted(f.step(k), Vec3::Zero(), true);
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace hapticd::loop
