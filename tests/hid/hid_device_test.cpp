// The HID Device against scripted devices: the PID start-up and shut-down sequences byte by
// byte, devices that refuse them, a device unplugged mid-run, a device that stops taking
// output reports, the report profile's feature reports, and the crash handler's last word.
#include <gtest/gtest.h>

#include <cerrno>

#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/pid_protocol.h"
#include "fake_hid_device.h"
#include "hid_test_support.h"

namespace hapticd::drivers::hid {
namespace {

using testing::FakeHidDevice;
using Bytes = std::vector<std::uint8_t>;

PidLayout reference_layout() {
  const auto p = parse_report_descriptor(pid_reference_descriptor());
  return *find_pid_layout(*p.descriptor, kGenericDesktopX, kReferenceSequenceUsage).layout;
}

// A Block Load answer with this block and status.
Bytes block_load(const PidLayout& l, std::int64_t block, const Choice& status) {
  Bytes r = make_report(l.block_load, true);
  auto d = std::span<std::uint8_t>(r).subspan(1);
  set_slot(d, l.bl_block, block);
  choose(d, status);
  return r;
}

std::int64_t slot(const Bytes& report, const Slot& s) {
  return get_slot(std::span<const std::uint8_t>(report).subspan(1), s);
}
bool is(const Bytes& report, const Choice& c) {
  return chosen(std::span<const std::uint8_t>(report).subspan(1), c);
}

struct PidRig {
  explicit PidRig(std::vector<std::string> sets = {})
      : layout(reference_layout()), fake(pid_reference_descriptor()) {
    fake.on_get_feature = [this](std::uint8_t id) {
      return id == layout.block_load.id ? block_load(layout, 3, load_status) : Bytes{};
    };
    load_status = layout.bl_success;
    device = std::make_unique<HidDevice>(
        testing::settings_of(testing::load_example("hid-pid.yaml", sets)), fake.opener(), 1e-3);
  }
  PidLayout layout;
  Choice load_status;
  FakeHidDevice fake;
  std::unique_ptr<HidDevice> device;
};

TEST(HidPid, StartUpCreatesLoadsSetsStartsAndEnablesInThatOrder) {
  PidRig rig({"device.hid.pid.effect_duration_ms=0"});
  const PidLayout& l = rig.layout;
  rig.device->configure();
  rig.fake.wait_for(3);
  auto m = rig.fake.received();
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].type, FrameType::kGetDescriptor);
  EXPECT_TRUE(is(m[1].payload, l.dc_stop_all)) << "output off at configure";
  EXPECT_TRUE(is(m[2].payload, l.dc_disable));
  rig.device->enable();
  rig.fake.wait_for(10);
  m = rig.fake.received();
  ASSERT_EQ(m.size(), 10u);
  EXPECT_EQ(m[3].type, FrameType::kSetFeature);
  EXPECT_EQ(m[3].payload[0], l.create_effect.id);
  EXPECT_TRUE(is(m[3].payload, l.ce_constant));
  EXPECT_EQ(m[4].type, FrameType::kGetFeature);
  EXPECT_EQ(m[4].payload[0], l.block_load.id);
  const Bytes& effect = m[5].payload;  // Set Effect: the loaded block, constant, infinite
  EXPECT_EQ(effect[0], l.set_effect.id);
  EXPECT_EQ(slot(effect, l.se_block), 3);
  EXPECT_TRUE(is(effect, l.se_constant));
  EXPECT_EQ(slot(effect, l.se_duration), 0xFFFF) << "the null value: infinite";
  EXPECT_EQ(slot(effect, l.se_gain), 255);
  EXPECT_EQ(slot(effect, l.se_axis_x), 1);
  // DirectInput's polar angle, where the force comes from: 270 degrees pushes toward +X.
  EXPECT_EQ(slot(effect, l.se_direction), 27000) << "270 degrees: toward +X";
  EXPECT_EQ(m[6].payload[0], l.set_constant.id);
  EXPECT_EQ(slot(m[6].payload, l.sc_block), 3);
  EXPECT_EQ(slot(m[6].payload, l.sc_magnitude), 0);
  EXPECT_EQ(slot(m[7].payload, l.dg_gain), 255);
  EXPECT_TRUE(is(m[8].payload, l.eo_start));
  EXPECT_EQ(slot(m[8].payload, l.eo_block), 3);
  EXPECT_EQ(slot(m[8].payload, l.eo_loop_count), 1);
  EXPECT_TRUE(is(m[9].payload, l.dc_enable));

  ASSERT_EQ(rig.device->write(-4.25), IoStatus::kOk);
  rig.fake.wait_for(11);
  const Bytes force = rig.fake.outputs().back();
  EXPECT_EQ(force[0], l.set_constant.id);
  EXPECT_EQ(slot(force, l.sc_magnitude), -4250);

  rig.device->disable();  // zero, stop all, actuators off, the block freed
  rig.fake.wait_for(15);
  const auto out = rig.fake.outputs();
  ASSERT_GE(out.size(), 4u);
  EXPECT_EQ(slot(out[out.size() - 4], l.sc_magnitude), 0);
  EXPECT_TRUE(is(out[out.size() - 3], l.dc_stop_all));
  EXPECT_TRUE(is(out[out.size() - 2], l.dc_disable));
  EXPECT_EQ(out.back()[0], l.block_free.id);
  EXPECT_EQ(slot(out.back(), l.bf_block), 3);
}

TEST(HidPid, AFiniteEffectIsRestartedEveryHalfDuration) {
  PidRig rig;  // hid-pid.yaml: 100 ms at 1 kHz
  rig.device->configure();
  rig.device->enable();
  rig.fake.wait_for(10);
  ASSERT_GE(rig.fake.received().size(), 10u);
  EXPECT_EQ(slot(rig.fake.received()[5].payload, rig.layout.se_duration), 100);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(rig.device->write(1.0), IoStatus::kOk);
  rig.fake.wait_for(10 + 100 + 2);
  int starts = 0;
  for (const Bytes& r : rig.fake.outputs()) {
    starts += r[0] == rig.layout.effect_operation.id && is(r, rig.layout.eo_start) ? 1 : 0;
  }
  EXPECT_EQ(starts, 3) << "the start at enable, then one every 50 ticks";
}

// A restart due while the device takes nothing (its OUT queue full) is not lost: it goes at
// the first tick the queue takes again, ahead of that tick's force. Dropped, the effect would
// run out on the device half a duration later and the wall with it (a CI run's held axis went
// through its wall so, 4 s into a 4 s effect).
TEST(HidPid, ARestartTheFullQueueDroppedGoesAtTheNextTickThatWrites) {
  PidRig rig({"device.hid.limits.out_queue_full_fault=100000"});  // 100 ms effect at 1 kHz
  rig.device->configure();
  rig.device->enable();
  rig.fake.wait_for(10);
  rig.fake.reading.store(false);
  int ticks = 0;
  const auto tick = [&] {
    ASSERT_EQ(rig.device->write(1.0), IoStatus::kOk);
    ++ticks;
  };
  while (rig.device->hid_counts().out_queue_full == 0 && ticks < 100000) tick();
  ASSERT_GT(rig.device->hid_counts().out_queue_full, 0u) << "the queue never filled";
  const std::uint64_t before = rig.device->hid_counts().out_queue_full;
  int held = 0;
  for (; held < 50 || (ticks + 1) % 50 == 0; ++held) tick();  // a restart's tick, dropped
  rig.fake.reading.store(true);
  const std::uint64_t full = rig.device->hid_counts().out_queue_full;
  EXPECT_EQ(full - before, static_cast<std::uint64_t>(held))
      << "each tick the queue took nothing is one dropped tick, the pending restart's included";
  const std::size_t have = rig.fake.wait_quiet();  // what was queued, all taken
  tick();                                          // not a restart's own tick
  rig.fake.wait_for(have + 2);
  const auto out = rig.fake.outputs();
  ASSERT_GE(out.size(), 2u);
  EXPECT_TRUE(is(out[out.size() - 2], rig.layout.eo_start)) << "the dropped restart, sent now";
  EXPECT_EQ(out.back()[0], rig.layout.set_constant.id) << "then the tick's force";
  EXPECT_EQ(rig.device->hid_counts().out_queue_full, full) << "the queue took both";
}

TEST(HidPid, ABlockLoadThatFailsRefusesTheEnableAndLeavesTheDeviceOff) {
  PidRig rig;
  rig.load_status = rig.layout.bl_full;
  rig.device->configure();
  try {
    rig.device->enable();
    FAIL() << "enable succeeded";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("Block Load after Create New Effect: the device's "
                                         "effect memory is full (RAM pool available 0)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(rig.device->state(), DeviceState::kConfigured);
  // Configure's 2, Block Free of each of the 40 indexes (a pool left full by a crashed run is
  // freed once before giving up), and the undo's 3.
  rig.fake.wait_for(3 + 2 + 40 + 2 + 3);
  const auto out = rig.fake.outputs();
  ASSERT_GE(out.size(), 2u);
  EXPECT_TRUE(is(out.back(), rig.layout.dc_disable)) << "the half-done enable is undone";
}

TEST(HidPid, ABlockLoadOfAnotherReportIsRefused) {
  PidRig rig;
  rig.fake.on_get_feature = [](std::uint8_t) { return Bytes{0x07, 1, 1, 0, 0}; };
  rig.device->configure();
  EXPECT_THROW(
      {
        try {
          rig.device->enable();
        } catch (const DeviceError& e) {
          EXPECT_NE(std::string(e.what()).find("with report id 7, not feature report 66"),
                    std::string::npos)
              << e.what();
          throw;
        }
      },
      DeviceError);
}

TEST(HidPid, ADeviceWithoutSetConstantForceIsRefusedAtConfigure) {
  Bytes d = pid_reference_descriptor();
  const Bytes usage_73 = {0x09, 0x73};
  const auto at = std::search(d.begin(), d.end(), usage_73.begin(), usage_73.end());
  ASSERT_NE(at, d.end());
  at[1] = 0x74;  // Set Ramp Force Report instead
  FakeHidDevice fake(d);
  HidDevice device(testing::settings_of(testing::load_example("hid-pid.yaml")), fake.opener(),
                   1e-3);
  try {
    device.configure();
    FAIL() << "configured";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot run the pid profile: the report descriptor has "
                                         "no PID Set Constant Force report (0x0F:0x73)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(device.state(), DeviceState::kUnconfigured);
}

TEST(HidReportDevice, ALayoutTheDeviceDoesNotHaveIsRefusedAtConfigure) {
  const auto s = testing::settings_of(testing::load_example("hid-report.yaml"));
  ReportProfileLayout small = s->report;
  small.output.length = 4;
  FakeHidDevice fake(report_profile_descriptor(small));
  HidDevice device(s, fake.opener(), 1e-3);
  try {
    device.configure();
    FAIL() << "configured";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("the device's output report 2 has 4 data bytes, the "
                                         "layout needs 8 (device.hid.report.output.length)"),
              std::string::npos)
        << e.what();
  }
}

struct ReportRig {
  explicit ReportRig(std::vector<std::string> sets = {})
      : settings(testing::settings_of(testing::load_example("hid-report.yaml", sets))),
        fake(report_profile_descriptor(settings->report)),
        device(settings, fake.opener(), 1e-3) {}
  Bytes input(double position, std::uint32_t seq, std::uint32_t status) const {
    Bytes r(input_report_size(settings->report.input));
    encode_input({.position = {position}, .sequence = seq, .status = status},
                 settings->report.input, r);
    return r;
  }
  std::shared_ptr<const HidSettings> settings;
  FakeHidDevice fake;
  HidDevice device;
};

// Reads until something other than "no new data" comes back (the fake answers on its thread).
IoStatus read_until(Device& d, PositionSample& s) {
  IoStatus r = IoStatus::kNoNewData;
  for (int i = 0; i < 1000 && r == IoStatus::kNoNewData; ++i) {
    r = d.read(s);
    if (r == IoStatus::kNoNewData) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return r;
}

TEST(HidReportDevice, TheNewestOfSeveralPendingReportsIsUsed) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  for (std::uint32_t i = 0; i < 5; ++i) rig.fake.send_input(rig.input(0.001 * i, i, 0));
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  PositionSample s;
  ASSERT_EQ(rig.device.read(s), IoStatus::kOk);
  EXPECT_NEAR(s.position, 0.004, 1e-9);
  EXPECT_EQ(s.sequence, 4u);
  EXPECT_EQ(s.flags & (kSampleHasSequence | kSampleHasTime), kSampleHasSequence | kSampleHasTime);
  EXPECT_EQ(rig.device.hid_counts().superseded, 4u);
  EXPECT_EQ(rig.device.read(s), IoStatus::kNoNewData);
  EXPECT_EQ(rig.device.info().sequence_modulus, 256u);
}

TEST(HidReportDevice, AStatusFaultBitIsADeviceFaultWithTheBitsAsCode) {
  ReportRig rig;
  rig.device.configure();
  rig.fake.send_input(rig.input(0.0, 1, 0x01));
  PositionSample s;
  EXPECT_EQ(read_until(rig.device, s), IoStatus::kOk) << "output off: the mask does not apply";
  rig.device.enable();
  rig.fake.send_input(rig.input(0.0, 2, 0x05));
  EXPECT_EQ(read_until(rig.device, s), IoStatus::kDeviceFault);
  EXPECT_EQ(rig.device.fault().code, 0x05u);
  EXPECT_EQ(rig.device.describe_fault(),
            "hid: the device reported a fault: status 0x5 (fault bits 0x1 of mask 0x1)");
}

TEST(HidReportDevice, AnUnpluggedDeviceIsATransportFaultThatSaysSo) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  rig.fake.unplug();
  PositionSample s;
  EXPECT_EQ(rig.device.read(s), IoStatus::kTransportFault);
  EXPECT_EQ(rig.device.fault().code, static_cast<std::uint32_t>(ENODEV));
  EXPECT_NE(rig.device.describe_fault().find("the device is gone"), std::string::npos);
  EXPECT_NE(rig.device.write(1.0), IoStatus::kOk);
  rig.device.disable();  // never throws, even with the device gone
  rig.device.close();
}

TEST(HidReportDevice, ADeviceThatTakesNoReportsFaultsAfterTheConfiguredTicks) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  rig.fake.reading.store(false);
  IoStatus w = IoStatus::kOk;
  int writes = 0;
  while (w == IoStatus::kOk && writes < 100000) {
    w = rig.device.write(1.0);
    ++writes;
  }
  EXPECT_EQ(w, IoStatus::kTransportFault);
  EXPECT_EQ(rig.device.fault().code, static_cast<std::uint32_t>(ENOBUFS));
  EXPECT_EQ(rig.device.hid_counts().out_queue_full, 10u);
  EXPECT_EQ(rig.device.describe_fault(),
            "hid: the device took no output report for 10 ticks in a row (OUT queue full)");
  rig.fake.reading.store(true);
}

TEST(HidReportDevice, FeatureReportsSetTheWatchdogGainAndAmplifier) {
  ReportRig rig({"device.hid.report.output.enable=",
                 "device.hid.report.enable_feature={report_id: 3, length: 1, field: {byte: 0, "
                 "type: u8}, on: 1, off: 0}",
                 "device.hid.report.gain_feature={report_id: 4, length: 1, field: {byte: 0, "
                 "type: u8}, value: 200}",
                 "device.hid.report.watchdog_feature={report_id: 5, length: 2, field: {byte: 0, "
                 "type: u16}, value: 50}"});
  rig.device.configure();
  rig.device.enable();
  std::vector<Bytes> features;
  for (const auto& m : rig.fake.received()) {
    if (m.type == FrameType::kSetFeature) features.push_back(m.payload);
  }
  ASSERT_EQ(features.size(), 4u);
  EXPECT_EQ(features[0], (Bytes{5, 50, 0})) << "the watchdog, at configure";
  EXPECT_EQ(features[1], (Bytes{3, 0})) << "amplifier off at configure";
  EXPECT_EQ(features[2], (Bytes{4, 200})) << "gain at enable";
  EXPECT_EQ(features[3], (Bytes{3, 1})) << "amplifier on";
}

TEST(HidReportDevice, TheKeepaliveMovesWithEveryReport) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  for (int i = 0; i < 3; ++i) ASSERT_EQ(rig.device.write(0.5), IoStatus::kOk);
  rig.fake.wait_for(5 + 3);
  const auto out = rig.fake.outputs();
  ASSERT_GE(out.size(), 3u);
  const std::size_t k = 1 + 3;  // keepalive: data byte 3
  EXPECT_EQ(out[out.size() - 3][k] + 1, out[out.size() - 2][k]);
  EXPECT_EQ(out[out.size() - 2][k] + 1, out[out.size() - 1][k]);
  EXPECT_EQ(out.back()[1], 0xF4);  // 0.5 N = 500 counts, little-endian
  EXPECT_EQ(out.back()[2], 0x01);
}

TEST(HidReportDevice, TheCrashHandlerSendsZeroAndOutputOff) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  ASSERT_EQ(rig.device.write(7.0), IoStatus::kOk);
  const std::size_t before = rig.fake.received().size() + 1;
  rig.device.emergency_stop();
  rig.fake.wait_for(before + 1);
  const Bytes last = rig.fake.outputs().back();
  EXPECT_EQ(last, (Bytes{2, 0, 0, 0, 0, 0, 0, 0, 0})) << "force 0, enable off";
}

}  // namespace
}  // namespace hapticd::drivers::hid
