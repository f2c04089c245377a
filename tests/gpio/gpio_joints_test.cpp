// The GPIO driver of several joints (device.gpio.joints, config/gpio-xy.yaml): the list's
// config errors named with their place; against the loopback peer, each joint's encoder decodes
// its own edges and each joint's force reaches its own motor driver, read and write allocate
// nothing, a fault of either joint (an edge storm, its motor driver's fault line, cut wires)
// faults the device with zero duty on every joint and the cause naming the joint; the XY table's
// hand comes to rest at F/K along the wall's normal (1, 1)/sqrt 2; the udev rules grant the
// chip once and export both channels.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "control/scene.h"
#include "drivers/gpio/gpio_device.h"
#include "drivers/gpio/gpio_settings.h"
#include "drivers/gpio/gpio_wire.h"
#include "loop/scene_tick.h"
#include "loop/servo_loop.h"
#include "scene_run.h"
#include "sim/joint_plant.h"
#include "sim/peers/gpio/gpio_peer.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers::gpio {
namespace {

bool mentions(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::string xy_text() {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/gpio-xy.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

config::Config load_xy(std::vector<std::string> sets = {}, const std::string& text = xy_text()) {
  std::vector<config::Override> o;
  for (const auto& s : sets) o.push_back(config::parse_override(s));
  o.push_back(config::parse_override("loop.clock=freerun"));
  return config::load_config_text(text, "gpio-xy.yaml", o, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

std::string xy_errors(std::vector<std::string> sets, const std::string& text = xy_text()) {
  try {
    load_xy(std::move(sets), text);
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const auto& m : e.messages()) all += m + "\n";
    return all;
  }
  return "";
}

// The loopback wire of several joints: the joint in an output's byte 2 and in an edge's line
// byte's high nibble, one more level byte per further joint; a joint past the last refused. A
// device of one joint's messages are byte for byte what they were (joint 0: zero bytes).
TEST(GpioJointsWire, TheJointTravelsInEveryMessageAndOneJointsBytesAreUnchanged) {
  std::array<std::uint8_t, wire::kMaxMessageSize> buf{};
  wire::Output o{12'345, 50'000, true, true, false};
  o.joint = 2;
  ASSERT_EQ(wire::encode_output(o, buf), wire::kOutputSize);
  EXPECT_EQ(buf[2], 2);
  wire::Output back;
  ASSERT_TRUE(wire::decode_output({buf.data(), wire::kOutputSize}, back));
  EXPECT_EQ(back.joint, 2);
  buf[2] = 3;
  EXPECT_FALSE(wire::decode_output({buf.data(), wire::kOutputSize}, back)) << "no joint 3";

  wire::Levels l{wire::kLevelA, 7};
  l.joint_count = 3;
  l.others = {wire::kLevelB, wire::kLevelFault};
  ASSERT_EQ(wire::encode_levels(l, buf), wire::kLevelsSize + 2);
  wire::Levels lb;
  ASSERT_TRUE(wire::decode_levels({buf.data(), wire::kLevelsSize + 2}, lb));
  EXPECT_EQ(lb.joint_count, 3u);
  EXPECT_EQ(lb.of(0), wire::kLevelA);
  EXPECT_EQ(lb.of(1), wire::kLevelB);
  EXPECT_EQ(lb.of(2), wire::kLevelFault);
  EXPECT_FALSE(wire::decode_levels({buf.data(), wire::kLevelsSize + 3}, lb)) << "a fourth joint";

  Edge e{5, 1, Line::kB, true};
  e.joint = 1;
  const std::size_t n = wire::encode_edges(10, {&e, 1}, buf);
  EXPECT_EQ(buf[wire::kEdgesHeaderSize + 12], 0x11);
  Edge eb;
  ASSERT_TRUE(wire::decode_edge({buf.data(), n}, 0, eb));
  EXPECT_EQ(eb.joint, 1);
  EXPECT_EQ(eb.line, Line::kB);
  buf[wire::kEdgesHeaderSize + 12] = 0x31;
  EXPECT_FALSE(wire::decode_edge({buf.data(), n}, 0, eb)) << "no joint 3";

  // One joint: the bytes of before (joint 0 where the formats had zeros).
  wire::Output one{1, 2, true, false, false};
  wire::encode_output(one, buf);
  EXPECT_EQ(buf[2], 0);
  EXPECT_EQ(wire::encode_levels({wire::kLevelA, 7}, buf), wire::kLevelsSize);
}

TEST(GpioJointsConfig, TheXyTableLoadsEachJointWithItsOwnLinesAndChannel) {
  const config::Config cfg = load_xy();
  const GpioSettings& s = gpio_settings(cfg);
  ASSERT_EQ(s.joints.size(), 2u);
  EXPECT_TRUE(s.listed);
  EXPECT_EQ(s.joint(0).line_a, 0u);
  EXPECT_EQ(s.joint(1).line_a, 4u);
  EXPECT_EQ(s.joint(1).line_fault, 7u);
  EXPECT_EQ(s.joint(0).pwm_channel, 0u);
  EXPECT_EQ(s.joint(1).pwm_channel, 1u);
  EXPECT_EQ(s.joint(1).chip, "gpiochip0") << "the section's chip, every joint's default";
  EXPECT_EQ(s.joint(1).counts_per_unit, 100000.0);
  // An entry's own chip, resolution and direction win over the section's.
  const config::Config own_cfg =
      load_xy({"device.gpio.joints[1].chip=gpiochip1", "device.gpio.joints[1].counts_per_unit=-1e5",
               "device.gpio.joints[1].direction_positive=low", "device.sim.counts_per_unit=1e5"});
  const GpioSettings& own = gpio_settings(own_cfg);
  EXPECT_EQ(own.joint(1).chip, "gpiochip1");
  EXPECT_EQ(own.joint(1).counts_per_unit, -1e5);
  EXPECT_FALSE(own.joint(1).direction_positive_high);
  EXPECT_TRUE(own.joint(0).direction_positive_high);
}

TEST(GpioJointsConfig, EveryRefusalIsNamedWithItsPlace) {
  // In the file: its name and line.
  std::string text = xy_text();
  text.replace(text.find("          b: 5"), 14, "          b: 2");
  std::string e = xy_errors({}, text);
  EXPECT_TRUE(mentions(e, "gpio-xy.yaml:")) << e;
  e = xy_errors({"device.gpio.joints[1].lines.b=2"});
  EXPECT_TRUE(mentions(e,
                       "device.gpio.joints[1].lines.b: line 2 of gpiochip0 twice: "
                       "device.gpio.joints[0].lines.direction and device.gpio.joints[1].lines.b"))
      << e;
  // The same line offset on another chip is another line.
  EXPECT_EQ(xy_errors({"device.gpio.joints[1].lines.b=2", "device.gpio.joints[1].chip=gpiochip1"}),
            "");
  e = xy_errors({"device.gpio.joints[1].chip=/dev/gpiochip0", "device.gpio.joints[1].lines.a=3"});
  EXPECT_TRUE(mentions(e, "device.gpio.joints[1].lines.a: line 3 of /dev/gpiochip0 twice")) << e;
  e = xy_errors({"device.gpio.joints[1].pwm.channel=0"});
  EXPECT_TRUE(mentions(e, "device.gpio.joints[1].pwm: /sys/class/pwm/pwmchip0/pwm0 twice")) << e;
  EXPECT_EQ(xy_errors({"device.gpio.joints[1].pwm={chip: 1, channel: 0}"}), "")
      << "channel 0 of another PWM chip";
  e = xy_errors({"device.gpio.joints[1].pwm={chip: 1}"});
  EXPECT_TRUE(mentions(e, "device.gpio.joints[1].pwm.channel: missing")) << e;
  e = xy_errors({"device.gpio.lines={a: 0, b: 1, direction: 2}"});
  EXPECT_TRUE(mentions(e,
                       "device.gpio.lines: is the one joint's of a device of one joint, beside "
                       "device.gpio.joints"))
      << e;
  e = xy_errors({"device.gpio.pwm.channel=0", "device.gpio.start_count=5"});
  EXPECT_TRUE(mentions(e, "device.gpio.pwm.channel: is the one joint's channel")) << e;
  EXPECT_TRUE(mentions(e, "device.gpio.start_count: is the one joint's")) << e;
  e = xy_errors({"device.kinematics.joints=3", "device.kinematics.scale=[1,1,1]",
                 "device.kinematics.sign=[1,1,1]",
                 "device.kinematics.workspace={lower: [-0.1, -0.1, -0.1], upper: [0.1, 0.1, 0.1]}",
                 "walls[0].point=[0.02, 0.02, 0]", "walls[0].normal=[1, 1, 0]",
                 "device.sim.operator.origin=[0, 0, 0]",
                 "device.sim.operator.direction=[1, 1, 0]"});
  EXPECT_TRUE(mentions(e,
                       "device.gpio: 2 joint(s) of encoder and PWM, but device.kinematics "
                       "(cartesian) has 3"))
      << e;
  e = xy_errors({"device.gpio.joints=[]"});
  EXPECT_TRUE(mentions(e, "device.gpio.joints: must be a list of 1 to 3 joints")) << e;
  e = xy_errors({"device.gpio.joints[0].lines.dirction=9"});
  EXPECT_TRUE(mentions(e, "device.gpio.joints[0].lines.dirction: unknown key")) << e;
  e = xy_errors({"device.gpio.joints[0].index_count=5"});
  EXPECT_TRUE(mentions(e, "device.gpio.joints[0].index_count: needs lines.index")) << e;
}

// The device of gpio-xy.yaml against its loopback peer, ticked by hand as the loop does it.
struct XyRig {
  explicit XyRig(const config::Config& c)
      : cfg(c), pair(wiring::find_driver("gpio").make_loopback(c)), runner(*pair.peer) {}
  ~XyRig() { pair.device->close(); }
  sim::gpio::GpioPeer& peer() { return dynamic_cast<sim::gpio::GpioPeer&>(*pair.peer); }
  Device& device() { return *pair.device; }
  IoStatus tick(std::span<const double> forces, std::span<PositionSample> s) {
    const IoStatus r = device().read(s);
    if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return r;
    const IoStatus w = device().write(forces);
    runner.wait_idle();
    return w == IoStatus::kOk ? r : w;
  }
  config::Config cfg;
  wiring::Loopback pair;
  sim::PeerRunner runner;
};

TEST(GpioJointsLoopback, EachJointDecodesItsOwnEdgesAndDrivesItsOwnChannel) {
  XyRig rig(load_xy({"device.sim.operator.setpoint={shape: constant, value: 0}"}));
  rig.device().configure();
  EXPECT_EQ(rig.device().info().joints, 2u);
  rig.device().enable();
  const std::array<double, 2> forces = {2.0, -5.0};
  std::array<PositionSample, 2> s{};
  const hapticd::testing::AllocationScope scope;
  for (int i = 0; i < 300; ++i) ASSERT_NE(rig.tick(forces, s), IoStatus::kDeviceFault);
  EXPECT_EQ(scope.count(), 0u) << "read/write of two joints over 300 ticks";
  // Joint 0's duty is 2/10 of the period, joint 1's 5/10: each reaches its own motor driver.
  EXPECT_EQ(rig.peer().duty_ns(0), 10'000u);
  EXPECT_EQ(rig.peer().duty_ns(1), 25'000u);
  const auto& gpio = dynamic_cast<const GpioDevice&>(rig.device());
  // Each joint moved with its own force, and its own encoder counted it.
  const kinematics::Vec3 q = rig.pair.peer->joint_plant()->joint_positions();
  EXPECT_GT(q[0], 0.001);
  EXPECT_LT(q[1], -0.001);
  EXPECT_NEAR(s[0].position, q[0], 2e-5);
  EXPECT_NEAR(s[1].position, q[1], 2e-5);
  EXPECT_GT(gpio.decoder(0).edges(), 100u);
  EXPECT_GT(gpio.decoder(1).edges(), gpio.decoder(0).edges()) << "joint 1 moved further";
  EXPECT_EQ(gpio.decoder(0).missed_edges() + gpio.decoder(1).missed_edges(), 0u);
  rig.device().disable();
  rig.runner.wait_idle();  // the peer has taken the zero
  EXPECT_EQ(rig.peer().duty_ns(0), 0u);
  EXPECT_EQ(rig.peer().duty_ns(1), 0u);
}

// A fault of joint `joint` (made by `inject`) faults the device: from the fault on, zero duty on
// both joints, the cause naming that joint.
template <typename Inject>
void expect_joint_fault(std::size_t joint, Inject inject, const std::string& cause) {
  SCOPED_TRACE("joint " + std::to_string(joint));
  XyRig rig(load_xy({"device.sim.operator.setpoint={shape: constant, value: 0}"}));
  rig.device().configure();
  rig.device().enable();
  const std::array<double, 2> forces = {1.5, 1.5};
  std::array<PositionSample, 2> s{};
  for (int i = 0; i < 20; ++i) {
    const IoStatus r = rig.tick(forces, s);  // the first read precedes any period: no data
    ASSERT_TRUE(r == IoStatus::kOk || r == IoStatus::kNoNewData) << rig.device().describe_fault();
  }
  ASSERT_NE(rig.peer().duty_ns(0), 0u);
  ASSERT_NE(rig.peer().duty_ns(1), 0u);
  ASSERT_TRUE(inject(rig));
  IoStatus r = IoStatus::kOk;
  for (int i = 0; i < 200 && (r == IoStatus::kOk || r == IoStatus::kNoNewData); ++i) {
    r = rig.tick(forces, s);
  }
  EXPECT_TRUE(r == IoStatus::kDeviceFault || r == IoStatus::kTransportFault);
  EXPECT_EQ(rig.device().state(), DeviceState::kFaulted);
  rig.device().write(forces);  // the loop keeps writing: the device passes zero on every joint
  rig.runner.wait_idle();
  EXPECT_EQ(rig.peer().duty_ns(1 - joint), 0u) << "the healthy joint's duty too";
  EXPECT_EQ(rig.peer().duty_ns(joint), 0u);
  EXPECT_TRUE(rig.peer().channel_enabled()) << "a stop is duty 0 on the enabled channels";
  const std::string why = rig.device().describe_fault();
  EXPECT_TRUE(mentions(why, cause)) << why;
}

TEST(GpioJointsLoopback, AnEdgeStormOnEitherJointZeroesBothAndNamesIt) {
  for (std::size_t j : {0u, 1u}) {
    expect_joint_fault(
        j, [j](XyRig& rig) { return rig.peer().inject_wire(sim::gpio::WireFault::kEdgeBurst, j); },
        "gpio: joint " + std::to_string(j) + " (gpiochip0 lines " + (j == 0 ? "0,1" : "4,5") +
            ", pwmchip0/pwm" + std::to_string(j) + "): encoder edges at");
  }
}

TEST(GpioJointsLoopback, EitherMotorDriversFaultLineZeroesBothAndNamesIt) {
  expect_joint_fault(
      1, [](XyRig& rig) { return rig.peer().inject_fault_line(1); },
      "joint 1 (gpiochip0 lines 4,5, pwmchip0/pwm1): the motor driver's fault line (line 7) went "
      "active");
  expect_joint_fault(
      0, [](XyRig& rig) { return rig.peer().inject_fault_line(0); },
      "joint 0 (gpiochip0 lines 0,1, pwmchip0/pwm0): the motor driver's fault line (line 3)");
}

TEST(GpioJointsLoopback, IllegalTransitionsOnJointOneFaultTheDevice) {
  expect_joint_fault(
      1,
      [](XyRig& rig) { return rig.peer().inject_wire(sim::gpio::WireFault::kIllegalPattern, 1); },
      "joint 1 (gpiochip0 lines 4,5, pwmchip0/pwm1): 5 encoder edges missed");
}

// `hapticd run --loopback --config config/gpio-xy.yaml` as the loop runs it: the hand pressed
// along the diagonal rests at F/K along the wall's normal, with no fault.
TEST(GpioJointsLoopback, TheXyTablesHandRestsAtForceOverStiffnessAlongTheDiagonal) {
  const config::Config cfg = load_xy();
  wiring::Loopback pair = wiring::find_driver("gpio").make_loopback(cfg);
  const sim::gpio::GpioPeer& peer = dynamic_cast<const sim::gpio::GpioPeer&>(*pair.peer);
  sim::PeerRunner runner(*pair.peer);
  sim::PacedDevice device(std::move(pair.device), runner);
  telemetry::SpscRing<telemetry::TickRecord> ring(4096);
  device.configure();
  device.enable();
  const loop::LoopResult r = hapticd::testing::run_scene_loop(cfg, device, 2000, &ring);
  device.close();
  ASSERT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
  EXPECT_GT(r.count(loop::kCounterContactTicks), 1000u);
  std::vector<telemetry::TickRecord> records(ring.size_approx());
  records.resize(ring.pop_many(records.data(), records.size()));
  ASSERT_EQ(records.size(), 2000u);
  double rest = 0.0;
  for (std::size_t k = 1500; k < 2000; ++k) rest += records[k].penetration / 500.0;
  const config::TaskWallConfig& wall = cfg.walls.front();
  const config::OperatorSpec& hand = cfg.device.sim.op;
  const double reach = 0.05 - wall.normal.dot(wall.point - hand.origin);
  const double expected = hand.stiffness * reach / (wall.law.stiffness + hand.stiffness);
  EXPECT_NEAR(rest, expected, 0.02 * expected) << "F/K along the diagonal";
  const kinematics::Vec3 q = peer.joint_plant()->joint_positions();
  EXPECT_NEAR(q[0], q[1], 2e-5) << "a diagonal press moves both joints alike";
  EXPECT_GT(q[0], 0.02) << "both motors moved the one table past the wall's point";
}

TEST(GpioJointsUdev, TheChipIsGrantedOnceAndEachChannelExported) {
  const config::Config cfg = load_xy();
  UdevRules rules(cfg, "hapticd");
  wiring::find_driver("gpio").udev_rules(cfg, rules);
  const std::string text = rules.text();
  std::size_t grants = 0;
  for (std::size_t at = 0; (at = text.find("KERNEL==\"gpiochip0\"", at)) != std::string::npos;
       ++at) {
    ++grants;
  }
  EXPECT_EQ(grants, 1u) << text;
  EXPECT_TRUE(mentions(text, "uses lines 0, 1, 2, 3, 4, 5, 6, 7")) << text;
  EXPECT_TRUE(mentions(text, "echo 0 >%S%p/export")) << text;
  EXPECT_TRUE(mentions(text, "echo 1 >%S%p/export")) << text;
  EXPECT_TRUE(mentions(text, "device.gpio.joints[1].pwm: channel 1 of pwmchip0")) << text;
  const config::Config other = load_xy({"device.gpio.joints[1].chip=gpiochip3"});
  UdevRules two(other, "hapticd");
  wiring::find_driver("gpio").udev_rules(other, two);
  const std::string two_chips = two.text();
  EXPECT_TRUE(mentions(two_chips, "KERNEL==\"gpiochip3\"")) << two_chips;
  EXPECT_TRUE(mentions(two_chips, "KERNEL==\"gpiochip0\"")) << two_chips;
}

}  // namespace
}  // namespace hapticd::drivers::gpio
