// The simulated HID firmwares (sim/peers/hid) as the host meets them, report by report, with
// no link between: what they play, and what they say when the device vanishes under them.
#include <gtest/gtest.h>

#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "drivers/hid/pid_protocol.h"
#include "hid_test_support.h"
#include "sim/peers/hid/hid_firmware.h"

namespace hapticd::drivers::hid {
namespace {

using Bytes = std::vector<std::uint8_t>;

// The PID firmware of config/hid-pid.yaml (100 ms effects at 1 kHz), with one constant-force
// effect created, started and the device enabled, as hid-pidff leaves it; its Direction in
// hundredths of a degree (27000: toward +X).
struct PidHost {
  explicit PidHost(std::int64_t direction = 27000)
      : fw(sim::hid::make_firmware(testing::load_example("hid-pid.yaml"), 0)),
        l(*find_pid_layout(*parse_report_descriptor(fw->descriptor()).descriptor, kGenericDesktopX)
               .layout) {
    Bytes create = make_report(l.create_effect, true);
    choose(std::span<std::uint8_t>(create).subspan(1), l.ce_constant);
    EXPECT_EQ(fw->on_set_feature(create, ignore), 0);
    out(l.set_effect, [&](auto d) {
      set_slot(d, l.se_block, 1);
      choose(d, l.se_constant);
      set_slot(d, l.se_duration, 100);
      set_slot(d, l.se_gain, 255);
      set_slot(d, l.se_direction, direction);
    });
    out(l.effect_operation, [&](auto d) {
      set_slot(d, l.eo_block, 1);
      choose(d, l.eo_start);
    });
    out(l.device_control, [&](auto d) { choose(d, l.dc_enable); });
  }
  template <class Fill>
  void out(const ReportRef& ref, Fill fill, const sim::hid::HidFirmware::Send& send = ignore) {
    Bytes r = make_report(ref, true);
    fill(std::span<std::uint8_t>(r).subspan(1));
    fw->on_output(r, send);
  }
  void force(std::int64_t m, const sim::hid::HidFirmware::Send& send = ignore) {
    out(
        l.set_constant,
        [&](auto d) {
          set_slot(d, l.sc_block, 1);
          set_slot(d, l.sc_magnitude, m);
        },
        send);
  }
  static void ignore(std::span<const std::uint8_t>) {}
  std::unique_ptr<sim::hid::HidFirmware> fw;
  PidLayout l;
};

TEST(HidFirmware, AFiniteEffectThatIsNotRestartedRunsOut) {
  PidHost host;
  host.force(5000);
  EXPECT_DOUBLE_EQ(host.fw->applied_force(), 5.0);
  for (int i = 0; i < 99; ++i) host.force(5000);
  EXPECT_DOUBLE_EQ(host.fw->applied_force(), 5.0) << "it plays for its whole 100 ms";
  host.force(5000);
  EXPECT_DOUBLE_EQ(host.fw->applied_force(), 0.0) << "then it has run out";
}

// The Direction is DirectInput's polar angle, where the force comes from, and the simulated
// device renders it as OpenFFBoard does (commit 160af910, EffectsCalculator.cpp,
// calcComponentForce: `result_torque = -forceVector * angle_ratio`, angle_ratio the sine of
// the direction): a positive magnitude at 90 degrees pushes toward -X, at 270 toward +X. A
// simulated device with the opposite sign (+sin) fails here.
TEST(HidFirmware, TheDirectionIsWhereTheForceComesFrom) {
  for (const auto& [direction, along] :
       std::vector<std::pair<std::int64_t, double>>{{27000, 1.0}, {9000, -1.0}, {0, 0.0}}) {
    PidHost host(direction);
    host.force(5000);
    EXPECT_NEAR(host.fw->applied_force(), 5.0 * along, 1e-9) << "direction " << direction;
    host.force(-5000);
    EXPECT_NEAR(host.fw->applied_force(), -5.0 * along, 1e-9) << "direction " << direction;
  }
}

// The device vanishes (another thread cuts the wire: the conformance suite's transport fault)
// while its own thread is still answering what came before. The person feels nothing from
// that instant; but what the firmware still sends says its amplifier is on, as it is: it never
// switched it off. Reporting it off made the host see a device fault where the wire was cut
// (Conformance.EveryFaultClassFaultsTheLoopWithZeroForce/hid_2, once in a Debian 12 run).
TEST(HidFirmware, AVanishedDeviceIsFeltAtOnceButNeverReportsItsAmplifierOff) {
  PidHost host;
  host.force(5000);
  ASSERT_DOUBLE_EQ(host.fw->applied_force(), 5.0);
  ASSERT_TRUE(host.fw->output_on());
  host.fw->vanish();
  EXPECT_EQ(host.fw->applied_force(), 0.0) << "felt at once";
  EXPECT_FALSE(host.fw->output_on());
  std::vector<Bytes> sent;
  host.force(4000, [&](std::span<const std::uint8_t> r) { sent.emplace_back(r.begin(), r.end()); });
  EXPECT_EQ(host.fw->applied_force(), 0.0) << "and stays so";
  for (const Bytes& r : sent) {
    if (!is_report(r, host.l.state, true)) continue;
    EXPECT_EQ(get_slot(data_of(std::span<const std::uint8_t>(r), host.l.state, true),
                       host.l.st_actuators_enabled),
              1)
        << "a state report says the amplifier went off by itself";
  }
  EXPECT_FALSE(sent.empty()) << "its thread still answers until it sees the wire cut";
}

}  // namespace
}  // namespace hapticd::drivers::hid
