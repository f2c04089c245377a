// The pid profile with two joints (issue 37, config/hid-pid-xy.yaml): one constant-force
// effect per axis, each selecting its own axis with its own Direction, created at the enable;
// each tick one Set Constant Force per joint and never a Set Effect (docs/drivers/hid.md,
// "Two axes"). Against the simulated board, which reads the effects as OpenFFBoard's
// HidFFB.cpp does, the scene presses the stick into the diagonal wall and it rests where the
// wall balances the hand.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <thread>

#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/hid_device.h"
#include "fake_hid_device.h"
#include "hid_test_support.h"
#include "hid_xy_run.h"

namespace hapticd::drivers::hid {
namespace {

using XyPidBytes = std::vector<std::uint8_t>;

std::vector<std::uint8_t> two_axis_descriptor() {
  PidReferenceOptions o;
  o.axes = 2;
  o.sequence = false;  // config/hid-pid-xy.yaml reads no counter
  return pid_reference_descriptor(o);
}

std::int64_t xy_slot(const XyPidBytes& report, const Slot& s) {
  return get_slot(std::span<const std::uint8_t>(report).subspan(1), s);
}

// The fake board of two_axis_descriptor(), each Create New Effect given the next block.
struct XyPidRig {
  explicit XyPidRig(std::vector<std::string> sets)
      : sets_(std::move(sets)),
        fake(two_axis_descriptor()),
        layout(*find_pid_layout(*parse_report_descriptor(two_axis_descriptor()).descriptor, xy)
                    .layout) {
    fake.on_get_feature = [this](std::uint8_t id) {
      XyPidBytes r = make_report(layout.block_load, true);
      if (id != layout.block_load.id) return XyPidBytes{};
      const auto d = std::span<std::uint8_t>(r).subspan(1);
      const bool room = blocks < capacity;
      set_slot(d, layout.bl_block, room ? ++blocks : 0);
      choose(d, room ? layout.bl_success : layout.bl_full);
      return r;
    };
    device = std::make_unique<HidDevice>(
        testing::settings_of(testing::load_example("hid-pid-xy.yaml", sets_)), fake.opener(), 2e-3);
  }
  // The Set Effect reports the board received, in order.
  std::vector<XyPidBytes> set_effects() {
    std::vector<XyPidBytes> out;
    for (const XyPidBytes& r : fake.outputs()) {
      if (r[0] == layout.set_effect.id) out.push_back(r);
    }
    return out;
  }
  // The board reports on change (OpenFFBoard): the enable waits for its first report, which
  // the fake sends while the enable runs.
  void enable() {
    std::thread board([this] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      fake.send_input(make_report(layout.position_report, true));
    });
    device->enable();
    board.join();
  }
  static constexpr std::uint32_t xy[] = {kGenericDesktopX, kGenericDesktopY};
  std::vector<std::string> sets_;
  testing::FakeHidDevice fake;
  PidLayout layout;
  std::int64_t blocks = 0, capacity = 40;  // the board's effect pool
  std::unique_ptr<HidDevice> device;
};

TEST(HidPidTwoAxes, EachAxisHasItsOwnEffectAndATickSendsOneSetConstantForceEach) {
  XyPidRig rig({"device.hid.pid.effect_duration_ms=0"});
  const PidLayout& l = rig.layout;
  rig.device->configure();
  EXPECT_EQ(rig.device->info().joints, 2u);
  rig.enable();
  // Descriptor, stop all, disable; two Create New Effect and Block Load exchanges, two Set
  // Effect, two zero forces, Device Gain, two starts, enable.
  rig.fake.wait_for(15);
  ASSERT_EQ(rig.fake.received().size(), 15u);
  const std::vector<XyPidBytes> effects = rig.set_effects();
  ASSERT_EQ(effects.size(), 2u);
  for (std::size_t j = 0; j < 2; ++j) {
    const XyPidBytes& e = effects[j];
    EXPECT_EQ(xy_slot(e, l.se_block), static_cast<std::int64_t>(j + 1));
    EXPECT_EQ(xy_slot(e, l.se_axis_x), j == 0 ? 1 : 0) << "effect " << j;
    EXPECT_EQ(xy_slot(e, l.se_axis_y), j == 1 ? 1 : 0) << "effect " << j;
    EXPECT_EQ(xy_slot(e, l.se_direction_enable), 0) << "each axis reads its own Direction";
  }
  // 0 and 360 degrees: the two ends of 0..36000, where OpenFFBoard's share is -1 on X and on Y.
  EXPECT_EQ(xy_slot(effects[0], l.se_direction), 0);
  EXPECT_EQ(xy_slot(effects[1], l.se_direction_y), 36000);

  // Distinct values, so joints swapped or one effect's magnitude sent twice show.
  const std::array<double, 2> forces{1.0, -0.5};
  const std::size_t before = rig.fake.outputs().size();
  ASSERT_EQ(rig.device->write(forces), IoStatus::kOk);
  rig.fake.wait_for(17);
  const auto out = rig.fake.outputs();
  ASSERT_EQ(out.size(), before + 2) << "two reports a tick";
  for (std::size_t j = 0; j < 2; ++j) {
    const XyPidBytes& r = out[before + j];
    EXPECT_EQ(r[0], l.set_constant.id);
    EXPECT_EQ(xy_slot(r, l.sc_block), static_cast<std::int64_t>(j + 1));
  }
  // 2 N m at the Magnitude's 10000 (config/hid-pid-xy.yaml's force_full_scale).
  EXPECT_EQ(xy_slot(out[before], l.sc_magnitude), 5000);
  EXPECT_EQ(xy_slot(out[before + 1], l.sc_magnitude), -2500);

  rig.device->disable();  // both zero, stop all, actuators off, both blocks freed
  rig.fake.wait_for(23);
  const auto end = rig.fake.outputs();
  ASSERT_GE(end.size(), 6u);
  EXPECT_EQ(xy_slot(end[end.size() - 6], l.sc_magnitude), 0);
  EXPECT_EQ(xy_slot(end[end.size() - 5], l.sc_magnitude), 0);
  EXPECT_EQ(xy_slot(end[end.size() - 5], l.sc_block), 2);
  EXPECT_EQ(xy_slot(end[end.size() - 2], l.bf_block), 1);
  EXPECT_EQ(xy_slot(end.back(), l.bf_block), 2);
  EXPECT_EQ(rig.set_effects().size(), 2u) << "no Set Effect after the enable";
}

TEST(HidPidTwoAxes, FiniteEffectsAreRestartedInTurnEveryHalfDuration) {
  XyPidRig rig({});  // 100 ms effects at 500 Hz: each restarted every 25 ticks
  rig.device->configure();
  rig.enable();
  rig.fake.wait_for(15);
  const std::array<double, 2> forces{0.1, 0.1};
  for (int i = 0; i < 50; ++i) ASSERT_EQ(rig.device->write(forces), IoStatus::kOk);
  rig.fake.wait_for(15 + 100 + 4);
  std::array<int, 2> starts{};
  for (const XyPidBytes& r : rig.fake.outputs()) {
    if (r[0] != rig.layout.effect_operation.id || xy_slot(r, rig.layout.eo_block) < 1) continue;
    ++starts[static_cast<std::size_t>(xy_slot(r, rig.layout.eo_block) - 1)];
  }
  EXPECT_EQ(starts[0], 3) << "the start at enable, then at ticks 25 and 50";
  EXPECT_EQ(starts[1], 3) << "the start at enable, then at ticks 24 and 49: a tick apart";
}

// Both effects' restarts fall due while the device takes nothing (its OUT queue full): neither
// is lost, and both go, in order, at the first tick the queue takes again, ahead of its forces.
TEST(HidPidTwoAxes, RestartsTheFullQueueDroppedAllGoAtTheNextTickThatWrites) {
  XyPidRig rig({"device.hid.limits.out_queue_full_fault=100000"});  // restarts every 25 ticks
  rig.device->configure();
  rig.enable();
  rig.fake.wait_for(15);
  rig.fake.reading.store(false);
  const std::array<double, 2> forces{0.1, 0.1};
  int ticks = 0;
  const auto tick = [&] {
    ASSERT_EQ(rig.device->write(forces), IoStatus::kOk);
    ++ticks;
  };
  while (rig.device->hid_counts().out_queue_full == 0 && ticks < 100000) tick();
  ASSERT_GT(rig.device->hid_counts().out_queue_full, 0u) << "the queue never filled";
  while ((ticks + 2) % 25 != 0) tick();  // the next tick is effect 1's restart, then effect 0's
  tick();
  tick();
  rig.fake.reading.store(true);
  const std::size_t have = rig.fake.wait_quiet();  // what was queued, all taken
  tick();                                          // not a restart's own tick
  rig.fake.wait_for(have + 4);
  const auto out = rig.fake.outputs();
  ASSERT_GE(out.size(), 4u);
  const PidLayout& l = rig.layout;
  for (const std::size_t back : {4u, 3u}) {
    EXPECT_EQ(out[out.size() - back][0], l.effect_operation.id) << back << " from the end";
    EXPECT_TRUE(
        chosen(std::span<const std::uint8_t>(out[out.size() - back]).subspan(1), l.eo_start));
  }
  EXPECT_EQ(xy_slot(out[out.size() - 4], l.eo_block), 2) << "effect 1's restart, due first";
  EXPECT_EQ(xy_slot(out[out.size() - 3], l.eo_block), 1) << "then effect 0's";
  EXPECT_EQ(out[out.size() - 2][0], l.set_constant.id) << "then the tick's forces";
  EXPECT_EQ(out.back()[0], l.set_constant.id);
}

// A board whose pool holds one effect: the second axis' effect is refused by name, output off.
TEST(HidPidTwoAxes, ABoardThatHoldsOneEffectIsRefusedAtTheEnable) {
  XyPidRig rig({});
  rig.capacity = 1;
  rig.device->configure();
  try {
    rig.device->enable();
    FAIL() << "enabled with one effect for two axes";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot hold the 2 effects (one per axis)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_NE(rig.device->state(), DeviceState::kActive);
}

// The setting a reversed force names (drivers/device_entry.h): each axis' Direction mirrored
// about its range's middle, which a linear reading turns into the opposite share.
TEST(HidPidTwoAxes, TheReversalMirrorsEachAxisDirection) {
  const config::Config plain = testing::load_example("hid-pid-xy.yaml");
  const ForceReversal f = wiring::find_driver("hid").force_reversal(plain);
  EXPECT_EQ(f.key, "device.hid.pid.directions_deg");
  EXPECT_EQ(f.now, "[0, 360]");
  EXPECT_EQ(f.reversed, "[360, 0]");
  const config::Config flipped =
      testing::load_example("hid-pid-xy.yaml", {f.key + "=" + f.reversed});
  EXPECT_EQ(testing::settings_of(flipped)->pid.directions_deg, (std::vector<double>{360.0, 0.0}));
}

TEST(HidPidTwoAxes, TheStickRestsInTheDiagonalWallWhereTheWallBalancesTheHand) {
  const config::Config cfg = testing::load_example("hid-pid-xy.yaml", {"loop.clock=freerun"});
  // 500 Hz: the press is at depth from 0.7 s to 2.2 s, ticks 350 to 1100.
  const testing::XyRun r = testing::run_xy(cfg, 1100);
  ASSERT_EQ(r.result.fault.cause, loop::FaultCause::kNone) << loop::describe(r.result.fault);
  EXPECT_EQ(r.allocations, 0u) << "the loop with both effects' reports allocates nothing";
  EXPECT_EQ(r.peer_force_after, 0.0);
  ASSERT_EQ(r.records.size(), 1100u);
  const double rest = testing::mean_penetration(r, 1000, 1100);
  const double expected = testing::balanced_penetration(cfg, 0.2);  // setpoint.depth
  const config::TaskWallConfig& wall = cfg.walls.front();
  EXPECT_NEAR(rest, expected, 0.02 * expected) << "F/K along the diagonal";
  EXPECT_NEAR(r.joints[0], r.joints[1], 1e-3) << "a diagonal press turns both axes alike";
  EXPECT_GT(r.joints[0], wall.point[0]) << "each axis' own effect moved it past the face";
  // Two Set Constant Force a tick, a restart of each effect every 25 ticks, and the enable's
  // zero forces: what reaches the board.
  const double per_tick =
      static_cast<double>(r.output_reports) / static_cast<double>(r.result.ticks);
  EXPECT_GE(per_tick, 2.0);
  EXPECT_LE(per_tick, 2.0 + 2.0 / 25.0 + 0.01);
  RecordProperty("rest_rad", std::to_string(rest));
  RecordProperty("expected_rad", std::to_string(expected));
  RecordProperty("output_reports_per_tick", std::to_string(per_tick));
}

}  // namespace
}  // namespace hapticd::drivers::hid
