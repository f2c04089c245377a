// The report profile with two joints (issue 37, config/hid-report-xy.yaml): each joint's force
// reaches its own field of the one output report and each joint's position comes from its own
// field of the one input report; against the simulated device, the servo loop of the scene
// presses the simulated XY stage into the diagonal wall as the sim driver's stage with the same
// delay does, and a fault leaves both joints without force.
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

using XyBytes = std::vector<std::uint8_t>;
using testing::run_xy;
using testing::XyRun;

TEST(HidTwoJoints, EachJointHasItsOwnFieldInBothReports) {
  const auto s = testing::settings_of(testing::load_example("hid-report-xy.yaml"));
  testing::FakeHidDevice fake(report_profile_descriptor(s->report));
  HidDevice device(s, fake.opener(), 1e-3);
  device.configure();
  EXPECT_EQ(device.info().joints, 2u);
  device.enable();
  // Distinct values, so joints swapped or one field read twice show.
  const std::array<double, 2> forces{1.5, -2.5};
  ASSERT_EQ(device.write(forces), IoStatus::kOk);
  // The tick's report is the first with a force: the enable's zero-force report may still be
  // the newest when a count of messages says enough arrived (an ASan run saw it so).
  XyBytes out;
  OutputValues v;
  for (int i = 0; i < 1000 && v.force[0] == 0.0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const auto all = fake.outputs();
    if (all.empty()) continue;
    out = all.back();
    ASSERT_TRUE(decode_output(out, s->report.output, v));
  }
  EXPECT_DOUBLE_EQ(v.force[0], 1.5);
  EXPECT_DOUBLE_EQ(v.force[1], -2.5);
  EXPECT_TRUE(v.enable);
  // The bytes themselves: joint 0's i16 at data byte 0, joint 1's at data byte 2 (after the id).
  EXPECT_EQ(static_cast<std::int16_t>(out[1] | out[2] << 8), 1500);
  EXPECT_EQ(static_cast<std::int16_t>(out[3] | out[4] << 8), -2500);

  XyBytes in(input_report_size(s->report.input));
  encode_input({.position = {0.001, -0.002}, .sequence = 1, .status = 0}, s->report.input, in);
  fake.send_input(in);
  std::array<PositionSample, 2> samples{};
  IoStatus r = IoStatus::kNoNewData;
  for (int i = 0; i < 1000 && r == IoStatus::kNoNewData; ++i) {
    r = device.read(samples);
    if (r == IoStatus::kNoNewData) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  ASSERT_EQ(r, IoStatus::kOk);
  EXPECT_NEAR(samples[0].position, 0.001, 1e-9);
  EXPECT_NEAR(samples[1].position, -0.002, 1e-9);
  EXPECT_EQ(samples[1].sequence, samples[0].sequence);
  EXPECT_EQ(samples[1].time_ns, samples[0].time_ns) << "one report: one time";
  EXPECT_EQ(device.read(std::span(samples).first(1)), IoStatus::kTransportFault)
      << "one sample for a device of two joints is refused";
  device.close();
}

// The setting the direction check names for a reversed force (drivers/device_entry.h), for the
// list form: given back with --set, it reverses every joint's force field and nothing else.
TEST(HidTwoJoints, TheReversalOfTheListFormIsAListTheConfigurationReads) {
  const config::Config plain = testing::load_example("hid-report-xy.yaml");
  const ForceReversal f = wiring::find_driver("hid").force_reversal(plain);
  EXPECT_EQ(f.key, "device.hid.report.output.forces");
  EXPECT_EQ(f.reversed,
            "[{byte: 0, type: i16, scale: -0.001, full_scale: 10000}, "
            "{byte: 2, type: i16, scale: -0.001, full_scale: 10000}]");
  const config::Config flipped =
      testing::load_example("hid-report-xy.yaml", {f.key + "=" + f.reversed});
  const OutputLayout& o = testing::settings_of(flipped)->report.output;
  const OutputLayout& was = testing::settings_of(plain)->report.output;
  ASSERT_EQ(o.joints(), 2u);
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_EQ(o.joint(j).field.scale, -was.joint(j).field.scale);
    EXPECT_EQ(o.joint(j).field.byte, was.joint(j).field.byte);
    EXPECT_EQ(o.joint(j).full_scale, was.joint(j).full_scale);
  }
  const ForceReversal back = wiring::find_driver("hid").force_reversal(flipped);
  EXPECT_EQ(back.reversed, f.now) << "reversed twice: as it was";
}

TEST(HidTwoJoints, TheStageRestsInTheDiagonalWallAsTheSimDriversDoes) {
  const config::Config cfg = testing::load_example("hid-report-xy.yaml", {"loop.clock=freerun"});
  const XyRun hid = run_xy(cfg, 2000);
  ASSERT_EQ(hid.result.fault.cause, loop::FaultCause::kNone) << loop::describe(hid.result.fault);
  EXPECT_LE(hid.result.count(loop::kCounterStaleTicks), 1u);
  EXPECT_GT(hid.result.count(loop::kCounterContactTicks), 1000u);
  EXPECT_FALSE(hid.peer_on_after) << "disabled: the amplifiers are off";
  EXPECT_EQ(hid.peer_force_after, 0.0);

  // At rest the hand's spring and the wall share the set-point's reach past the face along the
  // normal: K p = k_h (depth - n . (point - origin) - p). Mean over the hold's last 0.5 s.
  ASSERT_EQ(hid.records.size(), 2000u);
  const double rest = testing::mean_penetration(hid, 1500, 2000);
  const double expected = testing::balanced_penetration(cfg, 0.05);  // setpoint.depth
  EXPECT_NEAR(rest, expected, 0.02 * expected) << "F/K along the diagonal";
  EXPECT_NEAR(hid.joints[0], hid.joints[1], 2e-5) << "a diagonal press moves both joints alike";
  EXPECT_GT(hid.joints[0], 0.02) << "both forces moved the one stage past the wall's point";

  // The sim driver on the same file, with the HID driver's one sample of delay on the wall.
  const config::Config sim_cfg = testing::load_example(
      "hid-report-xy.yaml",
      {"device.driver=sim", "device.hid=null", "walls[0].delay_samples=1", "loop.clock=freerun"});
  const XyRun sim = run_xy(sim_cfg, 2000);
  ASSERT_EQ(sim.result.fault.cause, loop::FaultCause::kNone) << loop::describe(sim.result.fault);
  EXPECT_NEAR(hid.result.max_penetration, sim.result.max_penetration,
              0.05 * sim.result.max_penetration)
      << "hid " << hid.result.max_penetration * 1e3 << " mm, sim "
      << sim.result.max_penetration * 1e3 << " mm";
  RecordProperty("rest_mm", std::to_string(rest * 1e3));
  RecordProperty("penetration_hid_mm", std::to_string(hid.result.max_penetration * 1e3));
  RecordProperty("penetration_sim_mm", std::to_string(sim.result.max_penetration * 1e3));
}

// A wall across x alone, the hand pressing along the diagonal: x stops in the wall while y
// follows the hand freely. A force sent to the other joint's field, or a position read from
// it, moves the wrong axis, which the symmetric diagonal wall cannot show.
TEST(HidTwoJoints, AWallAcrossXStopsXAndLeavesYToTheHand) {
  const config::Config cfg = testing::load_example(
      "hid-report-xy.yaml",
      {"loop.clock=freerun", "walls[0].normal=[1, 0]", "walls[0].point=[0.02, 0]"});
  const XyRun r = run_xy(cfg, 2000);
  ASSERT_EQ(r.result.fault.cause, loop::FaultCause::kNone) << loop::describe(r.result.fault);
  const config::TaskWallConfig& wall = cfg.walls.front();
  const config::OperatorSpec& hand = cfg.device.sim.op;
  const kinematics::Vec3 setpoint = hand.origin + 0.05 * hand.direction;  // setpoint.depth
  const double expected = testing::balanced_penetration(cfg, 0.05);
  ASSERT_EQ(r.records.size(), 2000u);
  const double rest = testing::mean_penetration(r, 1500, 2000);
  EXPECT_NEAR(rest, expected, 0.02 * expected) << "F/K across x";
  EXPECT_NEAR(r.joints[0], wall.point[0] + expected, 1e-4) << "x held in the wall";
  EXPECT_NEAR(r.joints[1], setpoint[1], 1e-4) << "y at the hand's set-point: no wall force on y";
}

TEST(HidTwoJoints, ADeviceFaultInTheWallLeavesBothJointsWithoutForce) {
  const config::Config cfg = testing::load_example("hid-report-xy.yaml", {"loop.clock=freerun"});
  // Half of 3000 ticks: 1.5 s, held at depth in the wall.
  const XyRun r = run_xy(cfg, 3000, true);
  ASSERT_EQ(r.result.fault.cause, loop::FaultCause::kDeviceReported)
      << loop::describe(r.result.fault);
  EXPECT_GT(r.contact_before_fault, 500u) << "it faulted in the wall";
  // The simulated device switches its amplifiers off only when the host's report says so: the
  // driver's output-off report reached it, before any disable.
  EXPECT_FALSE(r.peer_on_at_fault) << "the fault's report switched both amplifiers off";
  EXPECT_EQ(r.commands_at_fault[0], 0.0);
  EXPECT_EQ(r.commands_at_fault[1], 0.0);
  EXPECT_FALSE(r.peer_on_after);
}

}  // namespace
}  // namespace hapticd::drivers::hid
