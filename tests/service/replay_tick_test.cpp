// Replay runs the loop's own tick (loop/tick.h) on what a log recorded, so a run's forces and
// observer energy come back bit for bit by construction - also for the ticks the loop treats
// specially: positions a device that reports on change held, stale ticks, skipped periods.
#include <gtest/gtest.h>

#include <cmath>

#include "config/config_loader.h"
#include "control/controller.h"
#include "control/passivity_observer.h"
#include "loop/servo_loop.h"
#include "scripted_device.h"
#include "service/commands/replay.h"
#include "telemetry/spsc_ring.h"

namespace hapticd::service {
namespace {

using telemetry::TickRecord;

// A device pressed into the wall and out again that says something new only every third
// tick: in between it reports on change with nothing changed (held), and now and then has
// nothing at all (stale).
IoStatus pressing(std::uint64_t k, PositionSample& s) {
  s.position = -0.004 + 0.008 * std::sin(0.002 * static_cast<double>(k / 3 * 3));
  if (k % 97 == 50) return IoStatus::kNoNewData;
  if (k % 3 != 0) s.flags = kSampleHeld;
  return IoStatus::kOk;
}

telemetry::LogContents run_and_record(const config::Config& cfg) {
  hapticd::testing::ScriptedDevice device;
  device.script = pressing;
  control::Controller law(control::make_control_law(cfg));
  telemetry::SpscRing<TickRecord> ring(8192);
  loop::LoopOptions o;
  o.sample.realtime = false;
  o.max_ticks = 3000;
  o.observer = control::observer_params(cfg, 0);  // the sim driver's declared delay
  loop::ServoLoop servo(device, law, &ring, o);
  const std::atomic<bool> stop{false};
  const loop::LoopResult r = servo.run(stop);
  EXPECT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
  telemetry::LogContents log;
  log.header.sample_period_s = cfg.loop.sample_period_s();
  log.header.config_text = cfg.effective_yaml;
  log.records.resize(ring.size_approx());
  log.records.resize(ring.pop_many(log.records.data(), log.records.size()));
  return log;
}

TEST(ReplayTick, HeldAndStaleTicksOfADeviceThatReportsOnChangeReplayBitForBit) {
  const config::Config cfg =
      config::load_embedded_default({{"safety.passivity_controller", "damp", "--set p"},
                                     {"device.damping", "4", "--set b"},
                                     {"safety.stale_fault_ticks", "5", "--set s"}});
  const telemetry::LogContents log = run_and_record(cfg);
  ASSERT_EQ(log.records.size(), 3000u);
  std::size_t held = 0, stale = 0, contact = 0;
  for (const TickRecord& r : log.records) {
    held += (r.flags & telemetry::kFlagHeld) ? 1 : 0;
    stale += (r.flags & telemetry::kFlagStale) ? 1 : 0;
    contact += (r.flags & telemetry::kFlagContact) ? 1 : 0;
  }
  EXPECT_GT(held, 1500u);
  EXPECT_GT(stale, 20u);
  EXPECT_GT(contact, 500u);
  const ReplayResult r = replay_log(log, "scripted", nullptr);
  EXPECT_TRUE(r.stopped.empty()) << r.stopped;
  EXPECT_EQ(r.compared, 3000u);
  EXPECT_EQ(r.differing, 0u) << "first at tick " << r.first_difference.value_or(0);
}

}  // namespace
}  // namespace hapticd::service
