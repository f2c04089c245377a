// The loop with the sim device: no allocation per tick, deterministic freerun records, a
// full ring that never blocks.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "alloc_counter.h"
#include "base/clock.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "freerun.h"
#include "loop/client_force.h"
#include "loop/servo_loop.h"
#include "sim/sim_device.h"

namespace hapticd::loop {
namespace {

using telemetry::SpscRing;
using telemetry::TickRecord;

struct Rig {
  explicit Rig(const config::Config& c)
      : cfg(c),
        device(cfg.device, cfg.loop.sample_period_s()),
        controller(control::make_control_law(cfg)) {
    device.configure();
    device.enable();
  }
  config::Config cfg;
  sim::SimDevice device;
  control::Controller controller;
};

std::vector<TickRecord> drain(SpscRing<TickRecord>& ring) {
  std::vector<TickRecord> out(ring.size_approx());
  out.resize(ring.pop_many(out.data(), out.size()));
  return out;
}

TEST(ServoLoop, NoHeapAllocationPerTickFreerun) {
  Rig rig(config::load_embedded_default());  // the demo: a hand pushes into the wall
  SpscRing<TickRecord> ring(4096);           // no consumer: it fills after 4096 ticks
  // A client's force on the joint too (loop/client_force.h), offered before the run.
  ClientForce client({2.0, 1'000'000'000'000, 1'000'000, 1.0, 0.001});
  client.offer(kinematics::Vec3(-0.5, 0.0, 0.0), base::monotonic_ns());
  LoopOptions o = freerun(20000);
  o.client_force = &client;
  ServoLoop loop(rig.device, rig.controller, &ring, o);
  const std::atomic<bool> stop{false};
  hapticd::testing::AllocationScope scope;
  const LoopResult r = loop.run(stop);
  EXPECT_EQ(scope.count(), 0u) << "allocations on the RT path over " << r.ticks << " ticks";
  EXPECT_EQ(r.ticks, 20000u);
  EXPECT_GT(r.count(loop::kCounterContactTicks), 1000u);  // the demo really pressed into the wall
  EXPECT_EQ(ring.dropped(), 20000u - 4096u);              // a full ring counts losses, never blocks
  std::vector<TickRecord> kept(4096);
  kept.resize(ring.pop_many(kept.data(), kept.size()));
  std::size_t pushed = 0;
  for (const TickRecord& rec : kept) pushed += rec.client_force[0] == -0.5 ? 1 : 0;
  EXPECT_GT(pushed, 1000u) << "the client's force acted on the joint once the check armed it";
}

TEST(ServoLoop, NoHeapAllocationWhileThePassivityControllerDamps) {
  // A wall the gate refuses (K T / 2 = 10 N s/m against b = 2): the observer goes negative
  // and the controller acts on most ticks, inside the allocation scope.
  Rig rig(config::load_embedded_default({{"wall.stiffness", "20000", "--set"}}));
  SpscRing<TickRecord> ring(4096);
  LoopOptions o = freerun(5000);
  o.observer = control::observer_params(rig.cfg, 0);
  o.observer.mode = config::PassivityControl::kDamp;
  ServoLoop loop(rig.device, rig.controller, &ring, o);
  const std::atomic<bool> stop{false};
  hapticd::testing::AllocationScope scope;
  const LoopResult r = loop.run(stop);
  EXPECT_EQ(scope.count(), 0u) << "allocations on the RT path over " << r.ticks << " ticks";
  EXPECT_GT(r.passivity.damped_ticks, 100u);
  EXPECT_TRUE(r.passivity.observed);
}

TEST(ServoLoop, NoHeapAllocationPerTickRealtime) {
  Rig rig(config::load_embedded_default({{"loop.rate_hz", "5000", "--set loop.rate_hz=5000"}}));
  SpscRing<TickRecord> ring(1 << 12);
  LoopOptions o;
  o.sample.realtime = true;
  o.sample.period_ns = 200'000;
  o.max_ticks = 2000;
  o.overrun_fault_streak = 1 << 30;  // a noisy host must not end the test early
  ServoLoop loop(rig.device, rig.controller, &ring, o);
  const std::atomic<bool> stop{false};
  hapticd::testing::AllocationScope scope;
  const LoopResult r = loop.run(stop);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(r.ticks, 2000u);  // skipped periods are counted apart, never as ticks
  EXPECT_EQ(loop.wake_latency().count(), r.ticks);
}

TEST(ServoLoop, FreerunRecordsAreByteIdenticalAcrossRuns) {
  std::vector<TickRecord> runs[2];
  for (auto& records : runs) {
    Rig rig(config::load_embedded_default({{"device.sim.noise_counts", "0.7", "--set x"}}));
    SpscRing<TickRecord> ring(4096);
    ServoLoop loop(rig.device, rig.controller, &ring, freerun(3000));
    const std::atomic<bool> stop{false};
    loop.run(stop);
    records = drain(ring);
  }
  ASSERT_EQ(runs[0].size(), 3000u);
  ASSERT_EQ(runs[1].size(), 3000u);
  EXPECT_EQ(std::memcmp(runs[0].data(), runs[1].data(), runs[0].size() * sizeof(TickRecord)), 0);
  // Freerun keeps host timing out of the records: that is what makes them reproducible.
  EXPECT_EQ(runs[0][2999].scheduled_ns, 2999 * 1'000'000LL);
  EXPECT_EQ(runs[0][2999].wake_latency_ns, 0);
  EXPECT_EQ(runs[0][2999].compute_ns, 0);
}

TEST(ServoLoop, StopFlagEndsTheLoopAtATickBoundary) {
  Rig rig(config::load_embedded_default());
  ServoLoop loop(rig.device, rig.controller, nullptr, freerun(0));
  std::atomic<bool> stop{true};
  EXPECT_EQ(loop.run(stop).ticks, 0u);
}

TEST(ServoLoop, RecordsCarryTheControllerOutput) {
  Rig rig(config::load_embedded_default());
  SpscRing<TickRecord> ring(4096);
  ServoLoop loop(rig.device, rig.controller, &ring, freerun(1500));
  const std::atomic<bool> stop{false};
  const LoopResult r = loop.run(stop);
  const std::vector<TickRecord> rec = drain(ring);
  ASSERT_EQ(rec.size(), 1500u);
  std::uint64_t contact = 0;
  for (const TickRecord& t : rec) {
    EXPECT_DOUBLE_EQ(t.penetration, t.position);  // wall at 0, normal +1
    if (t.flags & telemetry::kFlagContact) {
      ++contact;
      EXPECT_LT(t.force_commanded, 0.0);  // pushes back toward -x
    }
  }
  EXPECT_EQ(contact, r.count(loop::kCounterContactTicks));
  EXPECT_DOUBLE_EQ(r.max_penetration,
                   std::max_element(rec.begin(), rec.end(), [](auto& a, auto& b) {
                     return a.penetration < b.penetration;
                   })->penetration);
}

}  // namespace
}  // namespace hapticd::loop
