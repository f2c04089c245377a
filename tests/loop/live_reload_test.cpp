// A live reload as the RT thread sees it (loop/law_swap.h): the new law governs from exactly
// one tick boundary, continues the old one's histories (its forces are those of a controller
// that ran the old law up to that tick and the new one from it), a refusal is a marker and
// nothing else, and the RT thread allocates nothing through all of it.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "loop/law_swap.h"
#include "loop/servo_loop.h"
#include "sim/sim_device.h"

namespace hapticd::loop {
namespace {

using telemetry::SpscRing;
using telemetry::TickRecord;

config::Config demo(const std::string& stiffness) {
  // The demo's hand presses into a damped wall behind two samples of delay, so the
  // histories a swap must carry over (xi, the delay line) are all in use. It holds for 10 s:
  // a freerun loop runs up to a ring (1024 ticks) ahead of a starved consumer, so the swap
  // may land as late as tick 1700, when the demo's own 1 s hold has the hand withdrawing.
  return config::load_embedded_default({{"wall.stiffness", stiffness, "--set k"},
                                        {"wall.damping", "0.3", "--set b"},
                                        {"wall.delay_samples", "2", "--set d"},
                                        {"device.sim.operator.setpoint.start", "0", "--set s"},
                                        {"device.sim.operator.setpoint.hold", "10", "--set h"}});
}

// The RT side: runs the loop on its own thread and counts what that thread allocates.
struct RtRun {
  RtRun(Device& device, control::Controller& law, SpscRing<TickRecord>& ring, LawSwap& swap)
      : loop(device, law, &ring, options(swap)) {}
  static LoopOptions options(LawSwap& swap) {
    LoopOptions o;
    o.sample.realtime = false;
    o.wait_for_ring = true;  // the consumer below keeps every record
    o.law_swap = &swap;
    return o;
  }
  void start() {
    thread = std::thread([this] {
      const hapticd::testing::AllocationScope scope;
      result = loop.run(stop);
      allocations = scope.count();
      done = true;
    });
  }
  ServoLoop loop;
  std::atomic<bool> stop{false};
  std::atomic<bool> done{false};
  std::thread thread;
  LoopResult result;
  std::uint64_t allocations = 1;
};

// Pops records until `until` holds for the last one popped, or the loop has ended (a fault)
// and the ring is empty.
template <typename Until>
void consume(const RtRun& rt, SpscRing<TickRecord>& ring, std::vector<TickRecord>& out,
             Until until) {
  TickRecord buf[256];
  for (;;) {
    const bool ended = rt.done;
    const std::size_t n = ring.pop_many(buf, 256);
    out.insert(out.end(), buf, buf + n);
    if (n > 0 && until(out.back())) return;
    if (n == 0 && ended) return;
    if (n == 0) std::this_thread::yield();
  }
}

TEST(LiveReload, TheNewLawGovernsFromOneTickBoundaryWithoutAllocatingOnTheRtThread) {
  const config::Config before = demo("2000"), after = demo("3000");
  sim::SimDevice device(before.device, before.loop.sample_period_s());
  device.configure();
  device.enable();
  control::Controller first(control::make_control_law(before));
  SpscRing<TickRecord> ring(1024);
  LawSwap swap;
  RtRun rt(device, first, ring, swap);
  rt.start();

  std::vector<TickRecord> records;
  consume(rt, ring, records, [](const TickRecord& r) { return r.tick >= 400; });  // in contact
  swap.note_refused();  // a refused reload: a marker, the law stays
  auto second = std::make_unique<control::Controller>(control::make_control_law(after));
  ASSERT_TRUE(swap.offer(second.get()));
  consume(rt, ring, records, [&](const TickRecord& r) {
    return swap.swaps() == 1 && r.tick >= swap.last_swap_tick() + 600;
  });
  rt.stop = true;
  rt.thread.join();
  consume(rt, ring, records, [](const TickRecord&) { return true; });  // whatever is left
  EXPECT_EQ(rt.allocations, 0u) << "the RT thread allocated during a run with a live reload";
  EXPECT_EQ(swap.retire(), &first);  // the replaced law comes back to be destroyed off-RT
  EXPECT_EQ(&rt.loop.controller(), second.get());
  EXPECT_EQ(rt.result.count(loop::kCounterReloads), 1u);

  const std::uint64_t at = swap.last_swap_tick();
  // The reference: the old law up to the boundary, the new one continuing it from there.
  control::Controller ref_old(control::make_control_law(before));
  control::Controller ref_new(control::make_control_law(after));
  control::Controller* ref = &ref_old;
  int accepted = 0, refused = 0, contact_after = 0;
  for (const TickRecord& r : records) {
    if (r.marker == telemetry::kMarkerReloadRefused) ++refused;
    if (r.marker == telemetry::kMarkerReloadAccepted) {
      ++accepted;
      EXPECT_EQ(r.tick, at);
      ref_new.continue_from(ref_old);
      ref = &ref_new;
    }
    if (r.marker != telemetry::kMarkerNone) continue;
    const control::ControlOutput out = ref->step(r.position);
    ASSERT_EQ(out.force_computed, r.force_computed)
        << "tick " << r.tick << " (swap at " << at << ")";
    ASSERT_EQ(out.force_commanded, r.force_commanded) << "tick " << r.tick;
    if (r.tick >= at && (r.flags & telemetry::kFlagContact)) ++contact_after;
  }
  EXPECT_EQ(accepted, 1);
  EXPECT_EQ(refused, 1);
  EXPECT_GT(contact_after, 100) << "the new stiffness was felt (swap at tick " << at << ")";
  // And it is a different wall: the old law would have computed other forces after the swap.
  control::Controller old_only(control::make_control_law(before));
  bool differs = false;
  for (const TickRecord& r : records) {
    if (r.marker != telemetry::kMarkerNone) continue;
    const double f = old_only.step(r.position).force_computed;
    if (r.tick >= at && f != r.force_computed) differs = true;
    if (r.tick < at) {
      ASSERT_EQ(f, r.force_computed) << "tick " << r.tick;
    }
  }
  EXPECT_TRUE(differs);
}

TEST(LiveReload, TakeContinuesTheNewLawBeforeTheSwapIsPublished) {
  // The offering side destroys the replaced law as soon as it sees swaps() move
  // (service/run_control.cpp), so the RT thread must be done reading it by then: take()
  // continues the new law from it first. (The loop used to do that after take() returned, a
  // use-after-free window ThreadSanitizer caught in the end-to-end reload tests.)
  control::Controller old_law(control::make_control_law(demo("2000")));
  control::Controller ref_old(control::make_control_law(demo("2000")));
  control::Controller ref_new(control::make_control_law(demo("3000")));
  for (double x : {-0.001, 0.001, 0.002}) {  // armed, in contact, commands on their way
    old_law.step(x);
    ref_old.step(x);
  }
  control::Controller next(control::make_control_law(demo("3000")));
  LawSwap swap;
  ASSERT_TRUE(swap.offer(&next));
  ASSERT_EQ(swap.take(&old_law, 7), &next);
  EXPECT_EQ(swap.swaps(), 1u);
  EXPECT_EQ(swap.last_swap_tick(), 7u);
  EXPECT_EQ(swap.retire(), &old_law);
  ref_new.continue_from(ref_old);
  for (double x : {0.003, 0.0025, 0.001}) {
    const control::ControlOutput got = next.step(x), want = ref_new.step(x);
    EXPECT_EQ(got.force_computed, want.force_computed) << "x " << x;
    EXPECT_EQ(got.force_commanded, want.force_commanded) << "x " << x;
  }
}

TEST(LiveReload, AnOfferTheLoopNeverTookCanBeWithdrawn) {
  const config::Config cfg = demo("2000");
  control::Controller next(control::make_control_law(cfg));
  LawSwap swap;
  ASSERT_TRUE(swap.offer(&next));
  EXPECT_FALSE(swap.offer(&next)) << "one offer at a time";
  EXPECT_TRUE(swap.withdraw(&next));
  EXPECT_EQ(swap.swaps(), 0u);
  EXPECT_EQ(swap.retire(), nullptr);
  EXPECT_EQ(swap.take_refusals(), 0u);
}

// The offering side's wait (await_swap): a reload is answered "taken at tick N" only when
// the loop took it. A loop starved past the time-out, or one that ended, gets its offer
// withdrawn, so the service never reports a wall the loop is not rendering (CI once saw a
// starved daemon answer "accepted" for a law the loop never took).
TEST(LiveReload, AnOfferARunningLoopDoesNotTakeInTimeIsWithdrawn) {
  control::Controller next(control::make_control_law(demo("2000")));
  LawSwap swap;
  swap.loop_starting();
  ASSERT_TRUE(swap.offer(&next));
  EXPECT_EQ(await_swap(swap, &next, 0, std::chrono::milliseconds(30)), SwapOutcome::kTimedOut);
  control::Controller current(control::make_control_law(demo("2000")));
  EXPECT_EQ(swap.take(&current, 5), nullptr) << "withdrawn: a late tick must not take it";
  EXPECT_EQ(swap.swaps(), 0u);
}

TEST(LiveReload, AnOfferToALoopThatHasEndedIsWithdrawnWithoutWaiting) {
  control::Controller next(control::make_control_law(demo("2000")));
  LawSwap swap;  // no loop has started: as good as ended
  ASSERT_TRUE(swap.offer(&next));
  EXPECT_EQ(await_swap(swap, &next, 0, std::chrono::hours(1)), SwapOutcome::kLoopEnded);
  swap.loop_starting();
  swap.loop_ended();
  ASSERT_TRUE(swap.offer(&next));
  EXPECT_EQ(await_swap(swap, &next, 0, std::chrono::hours(1)), SwapOutcome::kLoopEnded);
}

TEST(LiveReload, AnOfferTakenByTheLoopIsReportedTakenAndTheLoopMarksItsEnd) {
  const config::Config cfg = demo("2000");
  sim::SimDevice device(cfg.device, cfg.loop.sample_period_s());
  device.configure();
  device.enable();
  control::Controller law(control::make_control_law(cfg));
  control::Controller next(control::make_control_law(demo("3000")));
  LawSwap swap;
  LoopOptions o;
  o.sample.realtime = false;
  o.law_swap = &swap;
  o.max_ticks = 2000000;
  ServoLoop loop(device, law, nullptr, o);
  std::atomic<bool> stop{false};
  swap.loop_starting();
  LoopResult result;
  std::thread rt([&] { result = loop.run(stop); });
  ASSERT_TRUE(swap.offer(&next));
  EXPECT_EQ(await_swap(swap, &next, 0, std::chrono::hours(1)), SwapOutcome::kTaken);
  EXPECT_EQ(swap.retire(), &law);
  stop = true;
  rt.join();
  EXPECT_EQ(result.count(loop::kCounterReloads), 1u);
  EXPECT_TRUE(swap.ended());
}

TEST(LiveReload, ContinuingFromAShorterDelayLineKeepsItsNewestCommands) {
  // d = 1 to d = 3: the commands already on their way are kept, the older slots are zero, as
  // if the longer line had been there all along.
  const config::Config d1 = config::load_embedded_default({{"wall.delay_samples", "1", "--set"}});
  const config::Config d3 = config::load_embedded_default({{"wall.delay_samples", "3", "--set"}});
  control::Controller a(control::make_control_law(d1)), b(control::make_control_law(d3));
  for (double x : {-0.001, 0.001, 0.002}) a.step(x);  // armed (was outside), in contact
  b.continue_from(a);
  // b's first command is f_0, computed outside the wall (0); its second f_1, the first contact
  // force a computed: -f_1 pushes back.
  const control::ControlOutput next = b.step(0.002);
  EXPECT_EQ(next.force_commanded, 0.0);
  const control::ControlOutput later = b.step(0.002);
  EXPECT_LT(later.force_commanded, 0.0);
  control::Controller d3_all_along(control::make_control_law(d3));
  double expected = 0.0;
  for (double x : {-0.001, 0.001, 0.002, 0.002, 0.002}) {
    expected = d3_all_along.step(x).force_commanded;
  }
  EXPECT_EQ(later.force_commanded, expected);
}

}  // namespace
}  // namespace hapticd::loop
