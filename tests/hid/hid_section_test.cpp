// device.hid as a person writes it: the example configurations load, and every mistake is
// reported at its line with the key that must change.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "config/config_loader.h"
#include "drivers/hid/hid_settings.h"
#include "wiring/registry.h"

namespace hapticd::drivers::hid {
namespace {

std::string file(const char* name) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/" + name);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

config::Config load(const std::string& text, std::vector<std::string> sets = {}) {
  std::vector<config::Override> o;
  for (const std::string& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(text, "hid.yaml", o, ".", wiring::driver_schemas());
}

// The messages of a load that must fail.
std::vector<std::string> errors(const std::string& text, std::vector<std::string> sets = {}) {
  try {
    load(text, std::move(sets));
  } catch (const config::ConfigError& e) {
    return e.messages();
  }
  ADD_FAILURE() << "loaded without error";
  return {};
}

bool has(const std::vector<std::string>& msgs, const std::string& text) {
  for (const std::string& m : msgs) {
    if (m.find(text) != std::string::npos) return true;
  }
  return false;
}

std::string all(const std::vector<std::string>& msgs) {
  std::string s;
  for (const std::string& m : msgs) s += m + "\n";
  return s;
}

const HidSettings& hid(const config::Config& c) {
  return dynamic_cast<const HidSettings&>(*c.device.settings);
}

TEST(HidConfig, TheExampleConfigurationsLoad) {
  const config::Config r = load(file("hid-report.yaml"));
  const HidSettings& s = hid(r);
  EXPECT_EQ(s.profile, Profile::kReport);
  EXPECT_EQ(*s.select.vendor_id, 0x1209);
  EXPECT_EQ(s.report.input.report_id, 1);
  EXPECT_EQ(s.report.input.fault_mask, 0x01u);
  EXPECT_DOUBLE_EQ(s.report.output.full_scale, 10000);
  EXPECT_TRUE(s.report.output.keepalive);
  EXPECT_EQ(s.writer_priority, 79);
  const config::Config p = load(file("hid-pid.yaml"));
  EXPECT_EQ(hid(p).profile, Profile::kPid);
  EXPECT_EQ(hid(p).pid.sequence_usage, 0u) << "a real PID device has no vendor counter";
  EXPECT_DOUBLE_EQ(hid(p).pid.effect_duration_ms, 100);
}

// One force report a tick, polled every `poll_ms`.
int delay_of_one_report(double poll_ms, double period_s) {
  HidSettings s;
  s.poll_interval_ms = poll_ms;
  return declared_delay_samples(s, period_s);
}

TEST(HidConfig, TheDeclaredDelayFollowsThePollingIntervalAndT) {
  EXPECT_EQ(delay_of_one_report(1.0, 1e-3), 1);    // bInterval 1 at 1 kHz
  EXPECT_EQ(delay_of_one_report(1.0, 4e-3), 0);    // 250 Hz: the round trip fits a period
  EXPECT_EQ(delay_of_one_report(4.0, 4e-3), 1);    // a wheel polled at 250 Hz
  EXPECT_EQ(delay_of_one_report(0.125, 1e-3), 0);  // high speed, one microframe
  EXPECT_EQ(delay_of_one_report(1.0, 0.5e-3), 3);  // 2 kHz over 1 ms polling
  const config::Config c = load(file("hid-report.yaml"), {"device.hid.poll_interval_ms=4"});
  EXPECT_EQ(wiring::find_driver("hid").declared_delay(c), 7);
}

TEST(HidConfig, OverlappingFieldsAreReportedAtTheirLine) {
  const auto e =
      errors(file("hid-report.yaml"), {"device.hid.report.input.sequence={byte: 1, type: u8}"});
  EXPECT_TRUE(has(e, "device.hid.report.input.sequence: bytes 1..1 overlap input.position"))
      << all(e);
  EXPECT_TRUE(has(e, "--set device.hid.report.input.sequence")) << all(e);
}

TEST(HidConfig, AFieldPastTheReportIsReportedInTheFile) {
  std::string text = file("hid-report.yaml");
  const std::string from = "keepalive: {byte: 3, type: u8}";
  text.replace(text.find(from), from.size(), "keepalive: {byte: 8, type: u8}");
  const auto line = 1 + std::count(text.begin(), text.begin() + text.find("keepalive:"), '\n');
  const auto e = errors(text);
  ASSERT_EQ(e.size(), 1u) << all(e);
  EXPECT_EQ(e[0].rfind("hid.yaml:" + std::to_string(line) +
                           ": device.hid.report.output.keepalive: bytes 8..8 lie past the "
                           "report's 8 data bytes",
                       0),
            0u)
      << e[0];
}

TEST(HidConfig, AForceThatCannotReachMaxForceIsRefused) {
  auto e = errors(file("hid-report.yaml"), {"device.max_force=20"});
  EXPECT_TRUE(has(e,
                  "device.hid.report.output.force: counts -10000..10000 x 0.001 N + 0 N "
                  "reach only -10..10 N, which cannot represent device.max_force +-20 N"))
      << all(e);
  e = errors(file("hid-pid.yaml"), {"device.max_force=20"});
  EXPECT_TRUE(has(e, "device.hid.pid.force_full_scale: cannot represent device.max_force 20 N"))
      << all(e);
}

TEST(HidConfig, MistakesAreNamed) {
  const auto e =
      errors(file("hid-report.yaml"),
             {"device.hid.select={vendor_id: 0x1ffff}", "device.hid.backend=usb",
              "device.hid.report.input.position.type=i64", "device.hid.report.output.force.scael=1",
              "device.hid.pid={}", "device.hid.limits.out_queue=0"});
  EXPECT_TRUE(has(e, "device.hid.select.vendor_id: must be an integer in 0..65535 (0xFFFF)"))
      << all(e);
  EXPECT_TRUE(has(e, "device.hid.backend: must be one of hidraw, libusb; got 'usb'")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.input.position.type: must be one of u8")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.output.force.scael: unknown key")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.pid: not used by profile report")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.limits.out_queue: must be")) << all(e);
}

// Issue 34 items 5 and 1: a field of any width at any bit, signed or not, 24-bit types, and
// a position that wraps; every misspelling named at its key.
TEST(HidConfig, BitFieldsTwentyFourBitTypesAndWrappingPositionsAreSpelledAndChecked) {
  const config::Config c =
      load(file("hid-report.yaml"),
           {"device.hid.report.input.position={byte: 0, bits: 12, signed: true, scale: 1.0e-5, "
            "wraps: true}",
            "device.hid.report.input.sequence={byte: 1, bit: 4, bits: 4}",
            "device.hid.report.input.velocity={byte: 4, type: i24, endian: big, scale: 1.0e-3}"});
  const InputLayout& in = hid(c).report.input;
  EXPECT_EQ(in.position.bits, 12u);
  EXPECT_TRUE(in.position.is_signed);
  EXPECT_TRUE(in.position_wraps);
  EXPECT_EQ(in.sequence->bit, 4u);
  EXPECT_EQ(in.sequence->bits, 4u);
  EXPECT_FALSE(in.sequence->is_signed);
  EXPECT_EQ(in.velocity->bits, 24u);
  EXPECT_EQ(in.velocity->endian, Endian::kBig);
  const auto e =
      errors(file("hid-report.yaml"),
             {"device.hid.report.input.position={byte: 0, type: i16, bits: 12, scale: 1}",
              "device.hid.report.input.sequence={byte: 2, bits: 40}",
              "device.hid.report.input.status={byte: 3, type: u8, signed: true}",
              "device.hid.report.input.velocity={byte: 4, bit: 9, bits: 4, scale: 1}",
              "device.hid.report.output.keepalive={byte: 3}",
              "device.hid.report.output.enable={byte: 2, type: f32, bit: 3}"});
  EXPECT_TRUE(has(e, "device.hid.report.input.position.bits: give type or bits, not both"))
      << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.input.sequence.bits: must be in 1..32, got '40'"))
      << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.input.status.signed: only with bits")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.input.velocity.bit: must be in 0..7")) << all(e);
  EXPECT_TRUE(has(e,
                  "device.hid.report.output.keepalive.type: missing (one of u8, i8, u16, "
                  "i16, u24, i24, u32, i32, f32; or bits: N"))
      << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.output.enable.bit: an f32 starts at bit 0")) << all(e);
  auto w = errors(file("hid-report.yaml"), {"device.hid.report.input.velocity={byte: 4, type: "
                                            "i16, scale: 1, wraps: true}"});
  EXPECT_TRUE(has(w, "device.hid.report.input.velocity.wraps: unknown key")) << all(w);
  w = errors(file("hid-report.yaml"), {"device.hid.report.input.position={byte: 4, type: f32, "
                                       "scale: 1, wraps: true}"});
  EXPECT_TRUE(has(w, "device.hid.report.input.position.wraps: only an integer field wraps"))
      << all(w);
}

TEST(HidConfig, ABitFieldThatOverlapsIsReportedAtItsLine) {
  std::string text = file("hid-report.yaml");
  const std::string from = "sequence: {byte: 2, type: u8}";
  text.replace(text.find(from), from.size(), "sequence: {byte: 1, bit: 3, bits: 4}");
  const auto line = 1 + std::count(text.begin(), text.begin() + text.find("sequence:"), '\n');
  const auto e = errors(text);
  ASSERT_EQ(e.size(), 1u) << all(e);
  EXPECT_EQ(e[0], "hid.yaml:" + std::to_string(line) +
                      ": device.hid.report.input.sequence: byte 1 bits 3..6 overlap "
                      "input.position (bytes 0..1)");
}

TEST(HidConfig, ASelectorThatMatchesEverythingIsRefused) {
  const auto e = errors(file("hid-report.yaml"), {"device.hid.select={interface: 0}"});
  EXPECT_TRUE(has(e, "device.hid.select: selects every HID device")) << all(e);
}

TEST(HidConfig, PidSettingsAreChecked) {
  const auto e = errors(
      file("hid-pid.yaml"),
      {"device.hid.pid.position={usage_page: 1, usage: 0x30, min: 1, max: 1}",
       "device.hid.pid.effect_duration_ms=1", "device.hid.pid.gain=0", "device.hid.pid.report={}"});
  EXPECT_TRUE(has(e, "device.hid.pid.position: min and max must differ")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.pid.effect_duration_ms: must be 0 (infinite) or at least two"))
      << all(e);
  EXPECT_TRUE(has(e, "device.hid.pid.gain: must be in (0, 1]")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.pid.report: unknown key")) << all(e);
}

TEST(HidConfig, MissingLayoutPartsAreNamed) {
  const auto e =
      errors(file("hid-report.yaml"), {"device.hid.report.output.force={byte: 0, type: i16}",
                                       "device.hid.report.input={report_id: 1, length: 8}"});
  EXPECT_TRUE(has(e, "device.hid.report.output.force.scale: missing")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.output.force.full_scale: missing")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.report.input.position: missing")) << all(e);
}

TEST(HidConfig, TheLivenessBoundBelongsToADeviceThatReportsOnChange) {
  auto e = errors(file("hid-report.yaml"), {"device.hid.liveness_ms=100"});
  EXPECT_TRUE(has(e, "device.hid.liveness_ms: only with reports_on_change: true")) << all(e);
  e = errors(file("hid-report.yaml"),
             {"device.hid.reports_on_change=true", "device.hid.liveness_ms=1"});
  EXPECT_TRUE(has(e, "device.hid.liveness_ms: must be at least two sample periods (2 ms)"))
      << all(e);
  e = errors(file("hid-report.yaml"), {"device.hid.report.output.enable={byte: 2, type: u8, "
                                       "on: 0xzz, off: 0}"});
  EXPECT_TRUE(has(e, "device.hid.report.output.enable.on: must be an integer in")) << all(e);
}

// Several joints (issue 37): the list forms, one field per joint of device.kinematics.
TEST(HidConfig, TheTwoJointExampleLoadsWithAFieldPerJoint) {
  const config::Config c = load(file("hid-report-xy.yaml"));
  const ReportProfileLayout& l = hid(c).report;
  ASSERT_EQ(l.input.joints(), 2u);
  ASSERT_EQ(l.output.joints(), 2u);
  EXPECT_EQ(l.input.joint(0).field.byte, 0u);
  EXPECT_EQ(l.input.joint(1).field.byte, 2u);
  EXPECT_EQ(l.output.joint(1).field.byte, 2u);
  EXPECT_DOUBLE_EQ(l.output.joint(1).full_scale, 10000);
  EXPECT_EQ(l.input.key(1), "input.positions[1]");
  const config::Config one_joint = load(file("hid-report.yaml"));  // owns the settings read below
  const ReportProfileLayout& one = hid(one_joint).report;
  EXPECT_EQ(one.input.joints(), 1u);
  EXPECT_EQ(one.output.key(0), "output.force") << "a one-joint file reads as it did";
}

TEST(HidConfig, AListOfTheWrongLengthOrBothFormsAreRefusedByName) {
  auto e = errors(file("hid-report-xy.yaml"),
                  {"device.hid.report.input.positions=[{byte: 0, type: i16, scale: 1.0e-5}, "
                   "{byte: 2, type: i16, scale: 1.0e-5}, {byte: 6, type: u8, scale: 1.0e-5}]"});
  EXPECT_TRUE(has(e,
                  "device.hid.report.input.positions: 3 field(s) for a mechanism of 2 "
                  "joint(s) (device.kinematics)"))
      << all(e);
  e = errors(file("hid-report-xy.yaml"),
             {"device.hid.report.output.forces=",
              "device.hid.report.output.force={byte: 0, type: i16, scale: 0.001, "
              "full_scale: 10000}"});
  EXPECT_TRUE(has(e,
                  "device.hid.report.output.force: 1 field(s) for a mechanism of 2 joint(s) "
                  "(device.kinematics): give output.forces"))
      << all(e);
  e = errors(file("hid-report-xy.yaml"),
             {"device.hid.report.input.position={byte: 6, type: u8, scale: 1.0e-5}"});
  EXPECT_TRUE(has(e,
                  "device.hid.report.input.positions: give position (one joint) or positions "
                  "(one per joint), not both"))
      << all(e);
  e = errors(file("hid-report-xy.yaml"), {"device.hid.report.input.positions=[]"});
  EXPECT_TRUE(has(e, "device.hid.report.input.positions: must be a list of 1 to 3 fields"))
      << all(e);
}

TEST(HidConfig, EachJointsFieldIsCheckedAtItsEntry) {
  std::string text = file("hid-report-xy.yaml");
  const std::string from = "- {byte: 2, type: i16, scale: 1.0e-5}  # joint 1, y";
  text.replace(text.find(from), from.size(), "- {byte: 1, type: i16, scale: 1.0e-5}");
  const auto line = 1 + std::count(text.begin(), text.begin() + text.find("{byte: 1,"), '\n');
  auto e = errors(text);
  ASSERT_EQ(e.size(), 1u) << all(e);
  EXPECT_EQ(e[0], "hid.yaml:" + std::to_string(line) +
                      ": device.hid.report.input.positions[1]: bytes 1..2 overlap "
                      "input.positions[0] (bytes 0..1)");
  e = errors(file("hid-report-xy.yaml"), {"device.max_force=[10, 20]"});
  EXPECT_TRUE(has(e,
                  "device.hid.report.output.forces[1]: counts -10000..10000 x 0.001 N + 0 N "
                  "reach only -10..10 N, which cannot represent device.max_force +-20 N"))
      << all(e);
  EXPECT_FALSE(has(e, "output.forces[0]")) << "joint 0 reaches its 10 N: " << all(e);
  e = errors(file("hid-report-xy.yaml"),
             {"device.hid.report.input.velocity={byte: 6, type: i16, scale: 1.0e-3}"});
  EXPECT_TRUE(has(e, "device.hid.report.input.velocity: one field for 2 joints")) << all(e);
  e = errors(file("hid-report-xy.yaml"),
             {"device.hid.report.input.positions=[{byte: 0, type: i16, scale: 1.0e-5}, "
              "{byte: 2, type: f32, scale: 1.0e-5, wraps: true}]",
              "device.hid.report.input.length=8"});
  EXPECT_TRUE(has(e, "device.hid.report.input.positions[1].wraps: only an integer field wraps"))
      << all(e);
}

TEST(HidConfig, TheTwoAxisPidExampleLoadsAPositionAndADirectionPerJoint) {
  const config::Config c = load(file("hid-pid-xy.yaml"));
  const PidSettings& p = hid(c).pid;
  ASSERT_EQ(p.joints(), 2u);
  EXPECT_EQ(p.positions[0].usage, kGenericDesktopX);
  EXPECT_EQ(p.positions[1].usage, kGenericDesktopY);
  EXPECT_DOUBLE_EQ(p.positions[1].max, 0.349066);
  ASSERT_EQ(p.directions_deg.size(), 2u);
  EXPECT_EQ(p.directions_deg[0], 0.0);
  EXPECT_EQ(p.directions_deg[1], 360.0);
  EXPECT_EQ(force_reports_per_tick(hid(c)), 2u);
  // Two reports out, one polling interval each, and one back: 3 ms, under two 2 ms periods.
  EXPECT_EQ(declared_delay_samples(hid(c), 2e-3), 1);
  EXPECT_EQ(declared_delay_samples(hid(c), 1e-3), 2);
  const config::Config one = load(file("hid-pid.yaml"));
  EXPECT_EQ(hid(one).pid.joints(), 1u) << "`position` is one joint's";
  EXPECT_EQ(force_reports_per_tick(hid(one)), 1u);
}

TEST(HidConfig, TwoAxesRefuseWhatTheirEffectsCannotDo) {
  const std::string xy = file("hid-pid-xy.yaml");
  auto e = errors(xy, {"device.hid.pid.directions_deg="});
  EXPECT_TRUE(has(e, "device.hid.pid.directions_deg: missing (each joint's effect's Direction"))
      << all(e);
  e = errors(xy, {"device.hid.pid.directions_deg=[0]", "device.hid.pid.direction_deg=270"});
  EXPECT_TRUE(has(e, "device.hid.pid.directions_deg: must be a list of 2 directions")) << all(e);
  EXPECT_TRUE(has(e, "device.hid.pid.direction_deg: one joint's only")) << all(e);
  e = errors(xy, {"device.hid.pid.directions_deg=[0, 400]"});
  EXPECT_TRUE(has(e, "device.hid.pid.directions_deg[1]: must be in [0, 360]")) << all(e);
  e = errors(xy, {"device.hid.pid.positions=[{usage_page: 1, usage: 0x30, min: -1, max: 1}]"});
  EXPECT_TRUE(has(e, "device.hid.pid.positions: 1 position(s) for a mechanism of 2 joint(s)"))
      << all(e);
  e = errors(xy, {"device.hid.pid.positions=[{usage_page: 1, usage: 0x30, min: -1, max: 1}, "
                  "{usage_page: 1, usage: 0x30, min: -1, max: 1}]"});
  EXPECT_TRUE(has(e, "device.hid.pid.positions[1]: the same usage as positions[0]")) << all(e);
  // Two reports a period, one a millisecond: 1 kHz cannot carry them.
  e = errors(xy, {"loop.rate_hz=1000"});
  EXPECT_TRUE(has(e,
                  "device.hid.pid.positions: 2 joints send 2 Set Constant Force reports a "
                  "period"))
      << all(e);
  EXPECT_TRUE(has(e, "lower loop.rate_hz to at most 500")) << all(e);
  e = errors(xy, {"device.hid.pid.effect_duration_ms=6"});
  EXPECT_TRUE(has(e, "device.hid.pid.effect_duration_ms: must be 0 (infinite) or at least four"))
      << all(e);
  // One joint's file given a second joint's Direction.
  e = errors(file("hid-pid.yaml"), {"device.hid.pid.directions_deg=[0, 360]"});
  EXPECT_TRUE(has(e, "device.hid.pid.directions_deg: two joints' only")) << all(e);
}

TEST(HidConfig, ThePidProfileDrivesOneOrTwoJoints) {
  const auto e = errors(file("hid-report-xy.yaml"),
                        {"device.hid.profile=pid", "device.hid.report=",
                         "device.hid.pid={position: {usage_page: 1, usage: 0x30, min: -0.1, "
                         "max: 0.1}, force_full_scale: 10, directions_deg: [0, 360]}"});
  EXPECT_TRUE(has(e, "device.hid.pid.position: 1 position(s) for a mechanism of 2 joint(s)"))
      << all(e);
}

}  // namespace
}  // namespace hapticd::drivers::hid
