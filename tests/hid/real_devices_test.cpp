// Issue 22: what real HID devices do that the simulated firmware never did, against scripted
// devices: a device that reports only on change (held still, then hung), reports replaced
// within a tick, reports longer than declared, the keep-alive across the output-off report,
// an effect pool a crashed run left full, the default PID fault mask against a declared
// Safety Switch that is never set, and the configuration keys that say all this.
#include <gtest/gtest.h>

#include <cerrno>
#include <thread>

#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/pid_protocol.h"
#include "fake_hid_device.h"
#include "hid_test_support.h"

namespace hapticd::drivers::hid {
namespace {

using testing::FakeHidDevice;
using Bytes = std::vector<std::uint8_t>;

struct ReportRig {
  explicit ReportRig(std::vector<std::string> sets = {})
      : settings(testing::settings_of(testing::load_example("hid-report.yaml", sets))),
        fake(report_profile_descriptor(settings->report)),
        device(settings, fake.opener(), 1e-3) {}
  Bytes input(double position, std::uint32_t seq) const {
    Bytes r(input_report_size(settings->report.input));
    encode_input({.position = {position}, .sequence = seq, .status = 0}, settings->report.input, r);
    return r;
  }
  std::shared_ptr<const HidSettings> settings;
  FakeHidDevice fake;
  HidDevice device;
};

const std::vector<std::string> kOnChange = {"device.hid.reports_on_change=true",
                                            "device.hid.liveness_ms=200"};

TEST(HidOnChange, HeldStillTheLastPositionIsTheSampleUntilTheLivenessBound) {
  ReportRig rig(kOnChange);
  rig.device.configure();
  {
    // Joined however enable() ends: a refused enable (a starved host) fails the test, not
    // the process.
    std::jthread first([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      rig.fake.send_input(rig.input(0.003, 7));
    });
    rig.device.enable();  // waits for the first report: the device says nothing until then
  }
  PositionSample s;
  ASSERT_EQ(rig.device.read(s), IoStatus::kOk);
  EXPECT_NEAR(s.position, 0.003, 1e-9);
  // Nothing more from the device for 40 ms: every read is the same position, no sequence.
  for (int i = 0; i < 40; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    PositionSample h;
    ASSERT_EQ(rig.device.read(h), IoStatus::kOk) << "read " << i;
    EXPECT_NEAR(h.position, 0.003, 1e-9);
    EXPECT_EQ(h.flags & kSampleHasSequence, 0) << "a held position is no new sample";
  }
  EXPECT_GE(rig.device.hid_counts().held, 40u);
  // A report within the bound keeps it alive; then silence past it is a hung device.
  rig.fake.send_input(rig.input(0.003, 8));
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_EQ(rig.device.read(s), IoStatus::kOk);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(rig.device.read(s), IoStatus::kTransportFault);
  EXPECT_EQ(rig.device.fault().code, static_cast<std::uint32_t>(ETIMEDOUT));
  EXPECT_NE(rig.device.describe_fault().find("no report for longer than device.hid.liveness_ms "
                                             "(200 ms): its firmware is hung"),
            std::string::npos)
      << rig.device.describe_fault();
}

TEST(HidOnChange, AnEveryPeriodDeviceStillReportsNoNewData) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  rig.fake.send_input(rig.input(0.001, 1));
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  PositionSample s;
  ASSERT_EQ(rig.device.read(s), IoStatus::kOk);
  EXPECT_EQ(rig.device.read(s), IoStatus::kNoNewData) << "the loop's stale check decides";
}

TEST(HidOnChange, AnEnableWithoutAnyReportWithinTheBoundIsRefused) {
  ReportRig rig(kOnChange);
  rig.device.configure();
  try {
    rig.device.enable();
    FAIL() << "enabled";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("sent no input report within device.hid.liveness_ms"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(rig.device.state(), DeviceState::kConfigured);
}

TEST(HidFastDevice, ReplacedReportsAreCountedAsTakenIn) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  for (std::uint32_t i = 10; i < 14; ++i) rig.fake.send_input(rig.input(0.001, i));
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  PositionSample s;
  ASSERT_EQ(rig.device.read(s), IoStatus::kOk);
  EXPECT_EQ(s.sequence, 13u);
  EXPECT_EQ(s.samples, 4u) << "the loop must know four samples arrived, not one";
}

TEST(HidMalformedLength, AReportLongerThanDeclaredIsCountedNotDecoded) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  Bytes longer = rig.input(0.002, 1);
  longer.push_back(0);  // one byte more than the descriptor's 8
  rig.fake.send_input(longer);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  PositionSample s;
  EXPECT_EQ(rig.device.read(s), IoStatus::kNoNewData);
  EXPECT_EQ(rig.device.hid_counts().too_long, 1u);
  EXPECT_EQ(rig.device.hid_counts().input_reports, 0u);
}

TEST(HidKeepalive, TheFirstEnabledReportMovesOnFromTheOutputOffReport) {
  ReportRig rig;
  rig.device.configure();
  rig.device.enable();
  ASSERT_EQ(rig.device.write(0.1), IoStatus::kOk);
  rig.device.disable();
  rig.device.enable();
  rig.fake.wait_for(12);
  const auto out = rig.fake.outputs();
  const std::size_t k = 1 + 3, on = 1 + 2;  // keepalive byte 3, enable byte 2
  for (std::size_t i = 1; i < out.size(); ++i) {
    EXPECT_NE(out[i][k], out[i - 1][k])
        << "report " << i << " repeats the keep-alive " << int(out[i][k]) << " (enable "
        << int(out[i][on]) << " after " << int(out[i - 1][on]) << ")";
  }
}

TEST(HidConfigKeys, EnableOnAndOffTakeHexLikeIdsAndMasks) {
  const config::Config c =
      testing::load_example("hid-report.yaml", {"device.hid.report.output.enable={byte: 2, "
                                                "type: u8, on: 0xa5, off: 0x5a}"});
  const auto s = testing::settings_of(c);
  EXPECT_EQ(s->report.output.enable->on, 0xA5);
  EXPECT_EQ(s->report.output.enable->off, 0x5A);
}

// PID: the Block Load answers "full" until every index was freed.
struct FullPoolRig {
  FullPoolRig() : fake(pid_reference_descriptor()) {
    const auto p = parse_report_descriptor(pid_reference_descriptor());
    l = *find_pid_layout(*p.descriptor, kGenericDesktopX).layout;
    fake.on_get_feature = [this](std::uint8_t id) {
      if (id != l.block_load.id) return Bytes{};
      Bytes r = make_report(l.block_load, true);
      auto d = std::span<std::uint8_t>(r).subspan(1);
      const bool freed = frees() >= 40;
      set_slot(d, l.bl_block, freed ? 1 : 0);
      choose(d, freed ? l.bl_success : l.bl_full);
      return r;
    };
    device = std::make_unique<HidDevice>(
        testing::settings_of(testing::load_example("hid-pid.yaml")), fake.opener(), 1e-3);
  }
  std::size_t frees() {
    std::size_t n = 0;
    for (const Bytes& r : fake.outputs()) n += r[0] == l.block_free.id ? 1 : 0;
    return n;
  }
  PidLayout l;
  FakeHidDevice fake;
  std::unique_ptr<HidDevice> device;
};

TEST(HidPidPool, APoolLeftFullIsFreedByIndexAndTheEnableGoesOn) {
  FullPoolRig rig;
  rig.device->configure();
  rig.device->enable();
  EXPECT_EQ(rig.device->state(), DeviceState::kActive);
  EXPECT_EQ(rig.frees(), 40u) << "Block Free of every index 1..40 the descriptor allows";
}

TEST(HidPidDefaults, ADeclaredSafetySwitchThatIsNeverSetDoesNotFault) {
  const auto s = testing::settings_of(testing::load_example("hid-pid.yaml"));
  EXPECT_EQ(s->pid.fault_mask, kPidActuatorsDisabled);
  EXPECT_EQ(PidSettings{}.fault_mask, kPidActuatorsDisabled) << "the code's default";
  EXPECT_EQ(s->pid.sequence_usage, 0u) << "no vendor counter a real PID device lacks";
  const auto o = testing::settings_of(testing::load_example("hid-openffboard.yaml"));
  EXPECT_EQ(*o->select.vendor_id, 0x1209);
  EXPECT_EQ(*o->select.product_id, 0xFFB0);
  EXPECT_EQ(o->pid.fault_mask & kPidSafetySwitchOff, 0u);
  EXPECT_EQ(o->pid.sequence_usage, 0u);
  EXPECT_TRUE(o->reports_on_change);
  EXPECT_GT(o->liveness_ms, 100.0) << "above OpenFFBoard's ~100 report-interval resend";
}

}  // namespace
}  // namespace hapticd::drivers::hid
