// The evdev driver with two axes (device.evdev.axes, config/evdev-joystick.yaml): the section
// read and every mistake named at its line; the force of both joints turned into one effect's
// direction and level (or one effect per axis) as <linux/input.h> encodes the direction, on
// both axes and both signs; and the driver against its simulated joystick (sim/peers/evdev):
// a press along the diagonal comes to rest at F/K along the wall's normal with either kind of
// effect, nothing allocated on the loop's thread, and a fault zeroes both axes.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <thread>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "control/scene.h"
#include "drivers/evdev/evdev_settings.h"
#include "loop/scene_tick.h"
#include "loop/servo_loop.h"
#include "scene_run.h"
#include "sim/joint_plant.h"
#include "sim/peers/evdev/evdev_peer.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers::evdev {
namespace {

std::string text_of(const char* file) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/" + file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

config::Config joystick(const std::vector<std::string>& sets = {},
                        const char* file = "evdev-joystick.yaml") {
  std::vector<config::Override> o;
  for (const std::string& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(text_of(file), file, o, ".", wiring::driver_schemas());
}

std::string errors(const std::vector<std::string>& sets, const char* file = "evdev-joystick.yaml") {
  try {
    joystick(sets, file);
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const std::string& m : e.messages()) all += m + "\n";
    return all;
  }
  return "(loaded)";
}

TEST(EvdevTwoAxesConfig, TheJoystickExampleLoadsAndTheOneAxisExampleIsUnchanged) {
  const config::Config c = joystick();
  const EvdevSettings& s = evdev_settings(c);
  EXPECT_EQ(s.joints, 2);
  EXPECT_EQ(s.axis.code, 0x00);
  EXPECT_EQ(s.second.code, 0x01);
  EXPECT_EQ(direction_of(s.axis.direction_deg), 0xC000) << "right: toward ABS_X's maximum";
  EXPECT_EQ(direction_of(s.second.direction_deg), 0x0000) << "down: toward ABS_Y's maximum";
  EXPECT_EQ(s.effect, EffectMode::kDirection);
  const config::Config one_cfg = joystick({}, "evdev.yaml");
  const EvdevSettings& one = evdev_settings(one_cfg);
  EXPECT_EQ(one.joints, 1);
  EXPECT_EQ(direction_of(one.direction_deg), 0xC000);
  // ff-memless turns a direction into whole degrees: one effect per axis is its default.
  const config::Config memless = joystick({"device.evdev.effect=", "device.evdev.ff_driver=memless",
                                           "loop.rate_hz=250", "device.evdev.poll_interval_ms=1"});
  EXPECT_EQ(evdev_settings(memless).effect, EffectMode::kPerAxis);
}

// How many axes, and which key gives them: the file and line of the key, the key, what is
// wrong.
TEST(EvdevTwoAxesConfig, TheAxesAreCountedAgainstTheKinematicsAtTheirKey) {
  EXPECT_NE(
      errors({"device.kinematics.joints=3", "device.kinematics.scale=[1, 1, 1]",
              "device.kinematics.sign=[1, 1, 1]",
              "device.kinematics.workspace={lower: [-0.05, -0.05, -0.05], upper: [0.05, "
              "0.05, 0.05]}",
              "device.sim.operator.origin=[0, 0, 0]", "device.sim.operator.direction=[1, 1, 0]",
              "walls[0].point=[0.01, 0.01, 0]", "walls[0].normal=[1, 1, 0]"})
          .find("device.evdev.axes: 2 axis(es) read as 2 joint(s), but device.kinematics "
                "(cartesian) has 3"),
      std::string::npos)
      << errors({"device.kinematics.joints=3"});
  const std::string beside = errors({"device.evdev.axis={code: ABS_X, min: -1, max: 1}"});
  EXPECT_NE(beside.find("evdev-joystick.yaml:"), std::string::npos) << beside;
  EXPECT_NE(beside.find("device.evdev.axes: refuses device.evdev.axis beside it"),
            std::string::npos)
      << beside;
  const std::string one_axis_two_joints =
      errors({"device.evdev.axes=", "device.evdev.axis={code: ABS_X, min: -0.05, max: 0.05}"});
  EXPECT_NE(one_axis_two_joints.find("device.evdev.axis: 1 axis(es) read as 1 joint(s), but "
                                     "device.kinematics (cartesian) has 2"),
            std::string::npos)
      << one_axis_two_joints;
  // A list of one entry is one axis: its direction_deg is the effect's, the section's refused.
  const std::vector<std::string> one_entry = {
      "device.evdev.axis=", "device.evdev.direction_deg=",
      "device.evdev.axes=[{code: ABS_X, min: -0.05, max: 0.05, direction_deg: 90}]"};
  const config::Config listed_cfg = joystick(one_entry, "evdev.yaml");
  const EvdevSettings& listed = evdev_settings(listed_cfg);
  EXPECT_EQ(listed.joints, 1);
  EXPECT_EQ(direction_of(listed.direction_deg), 0x4000);
  std::vector<std::string> both = one_entry;
  both.push_back("device.evdev.direction_deg=270");
  EXPECT_NE(errors(both, "evdev.yaml").find("device.evdev.direction_deg: one axis' only"),
            std::string::npos)
      << errors(both, "evdev.yaml");
  const std::string three =
      errors({"device.evdev.axes=[{code: ABS_X, min: -1, max: 1}, {code: ABS_Y, min: -1, max: 1}, "
              "{code: ABS_Z, min: -1, max: 1}]"});
  EXPECT_NE(three.find("device.evdev.axes: must be a list of 1 or 2 axes"), std::string::npos)
      << three;
}

// Each axis' direction, the effect and the full scale they need, named at the key.
TEST(EvdevTwoAxesConfig, EachDirectionAndEffectMistakeIsNamedAtItsKey) {
  const std::string parallel = errors({"device.evdev.axes[1].direction_deg=90"});
  EXPECT_NE(parallel.find("device.evdev.axes: both axes push along the effect's x"),
            std::string::npos)
      << parallel;
  const std::string oblique = errors({"device.evdev.axes[1].direction_deg=45"});
  EXPECT_NE(oblique.find("device.evdev.axes[1].direction_deg: must be 0 (down), 90 (left)"),
            std::string::npos)
      << oblique;
  const std::string twice = errors({"device.evdev.axes[1].code=ABS_X"});
  EXPECT_NE(twice.find("ABS_X twice"), std::string::npos) << twice;
  const std::string section_dir = errors({"device.evdev.direction_deg=270"});
  EXPECT_NE(section_dir.find("device.evdev.direction_deg: one axis' only"), std::string::npos)
      << section_dir;
  const std::string small = errors({"device.evdev.force_full_scale=4"});
  EXPECT_NE(small.find("device.evdev.force_full_scale: cannot represent both joints' "
                       "device.max_force together"),
            std::string::npos)
      << small;
  EXPECT_EQ(errors({"device.evdev.force_full_scale=3", "device.evdev.effect=per_axis"}), "(loaded)")
      << "per axis: each joint's own";
  const std::string effect = errors({"device.evdev.effect=both"});
  EXPECT_NE(effect.find("device.evdev.effect"), std::string::npos) << effect;
  const std::string one_effect = errors({"device.evdev.effect=direction"}, "evdev.yaml");
  EXPECT_NE(one_effect.find("device.evdev.effect: only with two axes"), std::string::npos)
      << one_effect;
}

// <linux/input.h>: 0x0000 down, 0x4000 left, 0x8000 up, 0xC000 right; ABS_X grows to the
// right, ABS_Y down (toward the user).
TEST(EvdevTwoAxesDirection, EachJointsForceBecomesTheDirectionThatPushesItsWay) {
  const config::Config cfg = joystick();
  const EvdevSettings& s = evdev_settings(cfg);
  const double fs = s.force_full_scale;
  struct Case {
    double f0, f1;
    std::uint16_t direction;
  };
  for (const Case c :
       {Case{1, 0, 0xC000}, Case{-1, 0, 0x4000}, Case{0, 1, 0x0000}, Case{0, -1, 0x8000},
        Case{1, 1, 0xE000}, Case{-1, 1, 0x2000}, Case{-1, -1, 0x6000}, Case{1, -1, 0xA000}}) {
    const DirectedLevel e = directed_level(c.f0, c.f1, s, 0x1234);
    EXPECT_EQ(e.direction, c.direction) << c.f0 << ", " << c.f1;
    EXPECT_EQ(e.level, force_level(std::hypot(c.f0, c.f1), fs));
    EXPECT_NEAR(plane_force(0, e.direction, e.level, s), c.f0, 2e-4 * fs) << "joint 0";
    EXPECT_NEAR(plane_force(1, e.direction, e.level, s), c.f1, 2e-4 * fs) << "joint 1";
  }
  EXPECT_EQ(directed_level(0.0, 0.0, s, 0x1234).direction, 0x1234) << "no force: kept";
  EXPECT_EQ(directed_level(0.0, 0.0, s, 0x1234).level, 0);
  // Any force: the components come back within a level step and the angle's rounding.
  for (double a = 0.0; a < 2.0 * std::numbers::pi; a += 0.01) {
    const double f0 = 4.0 * std::cos(a), f1 = 4.0 * std::sin(a);
    const DirectedLevel e = directed_level(f0, f1, s, 0);
    EXPECT_NEAR(plane_force(0, e.direction, e.level, s), f0,
                4.0 * std::numbers::pi / 65536 + fs / 0x7fff);
    EXPECT_NEAR(plane_force(1, e.direction, e.level, s), f1,
                4.0 * std::numbers::pi / 65536 + fs / 0x7fff);
  }
  // A device pushing the other way on joint 1 (direction_deg 180): the effect mirrors in y.
  const config::Config up = joystick({"device.evdev.axes[1].direction_deg=180"});
  EXPECT_EQ(directed_level(0, 1, evdev_settings(up), 0).direction, 0x8000);
  EXPECT_EQ(directed_level(1, 1, evdev_settings(up), 0).direction, 0xA000);
}

// The driver against its simulated joystick, paced as a loopback run.
struct Loopback {
  explicit Loopback(const config::Config& c)
      : cfg(c),
        pair(wiring::find_driver("evdev").make_loopback(cfg)),
        peer(dynamic_cast<sim::evdev::SocketEvdevPeer&>(*pair.peer)),
        runner(*pair.peer),
        device(std::move(pair.device), runner) {}
  ~Loopback() { device.close(); }
  config::Config cfg;
  wiring::Loopback pair;
  sim::evdev::SocketEvdevPeer& peer;
  sim::PeerRunner runner;
  sim::PacedDevice device;
};

// Each joint's force, written through the driver, pushes the simulated joystick's joint its way.
TEST(EvdevTwoAxesLoopback, AForceOnEitherJointPushesThatJointItsWay) {
  for (const char* effect : {"direction", "per_axis"}) {
    Loopback rig(joystick({std::string("device.evdev.effect=") + effect, "loop.clock=freerun"}));
    rig.device.configure();
    EXPECT_EQ(rig.device.info().joints, 2u);
    rig.device.enable();
    std::array<PositionSample, 2> s{};
    for (const std::array<double, 2> f :
         {std::array<double, 2>{2.0, 0.0}, {0.0, 2.0}, {-2.0, 0.0}, {0.0, -2.0}, {1.5, -1.0}}) {
      ASSERT_EQ(rig.device.write(f), IoStatus::kOk);
      rig.runner.wait_idle();
      EXPECT_NEAR(rig.peer.joint_force(0), f[0], 1e-3) << effect;
      EXPECT_NEAR(rig.peer.joint_force(1), f[1], 1e-3) << effect;
      rig.device.read(s);
    }
    const kinematics::Vec3 v = rig.peer.joint_plant()->joint_velocities();
    EXPECT_GT(v[0], 0.0) << effect << ": the last push, +x";
    EXPECT_LT(v[1], 0.0) << effect << ": and -y";
    rig.device.disable();
    EXPECT_FALSE(rig.peer.output_on());
  }
}

// An entry's direction_deg turned by half a turn reverses that joint's force on a device that
// renders the direction as the header says, and only that joint's: the setting a device that
// pushes the other way needs (docs/drivers/evdev.md).
TEST(EvdevTwoAxesLoopback, AnAxisDirectionTurnedByHalfATurnReversesThatJointOnly) {
  for (const char* effect : {"direction", "per_axis"}) {
    Loopback rig(joystick({std::string("device.evdev.effect=") + effect, "loop.clock=freerun",
                           "device.evdev.axes[1].direction_deg=180"}));
    rig.device.configure();
    rig.device.enable();
    const std::array<double, 2> push{1.5, 2.0};
    ASSERT_EQ(rig.device.write(push), IoStatus::kOk);
    rig.runner.wait_idle();
    EXPECT_NEAR(rig.peer.joint_force(0), 1.5, 1e-3) << effect;
    EXPECT_NEAR(rig.peer.joint_force(1), -2.0, 1e-3) << effect;
    rig.device.disable();
  }
}

loop::LoopResult run_scene(const config::Config& cfg, Device& device, std::uint64_t ticks,
                           std::uint64_t* allocations) {
  device.configure();
  device.enable();
  return hapticd::testing::run_scene_loop(cfg, device, ticks, nullptr, allocations);
}

// The press of the example along the diagonal: at rest the hand's spring and the wall share
// the set-point's reach past the face, K p = k_h (reach - p), with either kind of effect; the
// loop's thread allocates nothing.
TEST(EvdevTwoAxesLoopback, TheDiagonalPressRestsAtForceOverStiffnessWithEitherEffect) {
  for (const char* effect : {"direction", "per_axis"}) {
    Loopback rig(joystick({std::string("device.evdev.effect=") + effect, "loop.clock=freerun"}));
    std::uint64_t allocations = 1;
    const loop::LoopResult r = run_scene(rig.cfg, rig.device, 2000, &allocations);
    ASSERT_EQ(r.fault.cause, loop::FaultCause::kNone) << effect << ": " << loop::describe(r.fault);
    EXPECT_EQ(allocations, 0u) << effect;
    const sim::JointPlant& plant = *rig.peer.joint_plant();
    const config::TaskWallConfig& wall = rig.cfg.walls.front();
    const config::OperatorSpec& hand = rig.cfg.device.sim.op;
    const double reach = 0.03 - wall.normal.dot(wall.point - hand.origin);
    const double expected = hand.stiffness * reach / (wall.law.stiffness + hand.stiffness);
    const double depth = wall.normal.dot(plant.task_position() - wall.point);
    EXPECT_NEAR(depth, expected, 0.02 * expected) << effect << ": F/K along the diagonal";
    const kinematics::Vec3 q = plant.joint_positions();
    EXPECT_NEAR(q[0], q[1], 2e-5) << effect << ": a diagonal press moves both axes alike";
    EXPECT_GT(r.max_penetration, 0.0);
  }
}

// A fault on the device's side (it stops its effect, or vanishes): the run ends with zero on
// both axes.
TEST(EvdevTwoAxesLoopback, AFaultZeroesBothAxes) {
  for (const sim::PeerFault fault :
       {sim::PeerFault::kDeviceFault, sim::PeerFault::kTransportFault}) {
    for (const char* effect : {"direction", "per_axis"}) {
      Loopback rig(joystick({std::string("device.evdev.effect=") + effect, "loop.clock=freerun"}));
      rig.device.configure();
      rig.device.enable();
      const std::array<double, 2> push{2.0, -1.0};
      std::array<PositionSample, 2> s{};
      ASSERT_EQ(rig.device.write(push), IoStatus::kOk);
      rig.runner.wait_idle();
      ASSERT_NEAR(rig.peer.joint_force(1), -1.0, 1e-3);
      ASSERT_TRUE(rig.peer.inject(fault));
      IoStatus status = IoStatus::kOk;
      for (int i = 0; i < 10 && status == IoStatus::kOk; ++i) {
        status = rig.device.write(push);
        rig.runner.wait_idle();
        if (status == IoStatus::kOk) status = rig.device.read(s);
      }
      EXPECT_NE(status, IoStatus::kOk) << effect;
      EXPECT_EQ(rig.device.state(), DeviceState::kFaulted);
      rig.runner.wait_idle();
      EXPECT_EQ(rig.peer.joint_force(0), 0.0) << effect;
      EXPECT_EQ(rig.peer.joint_force(1), 0.0) << effect;
      EXPECT_FALSE(rig.peer.output_on());
    }
  }
}

// The crash handler's stop (Device::emergency_stop: a write of each effect's stop, nothing
// else): both axes' effects, with one effect per axis.
TEST(EvdevTwoAxesLoopback, TheEmergencyStopStopsEveryEffect) {
  for (const char* effect : {"direction", "per_axis"}) {
    Loopback rig(joystick({std::string("device.evdev.effect=") + effect, "loop.clock=freerun"}));
    rig.device.configure();
    rig.device.enable();
    const std::array<double, 2> push{2.0, -1.0};
    ASSERT_EQ(rig.device.write(push), IoStatus::kOk);
    rig.runner.wait_idle();
    ASSERT_NEAR(rig.peer.joint_force(0), 2.0, 1e-3) << effect;
    rig.device.emergency_stop();
    EXPECT_TRUE([&] {
      for (int i = 0; i < 200; ++i) {
        if (!rig.peer.output_on()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      return false;
    }()) << effect;
    EXPECT_EQ(rig.peer.joint_force(0), 0.0) << effect;
    EXPECT_EQ(rig.peer.joint_force(1), 0.0) << effect;
  }
}

}  // namespace
}  // namespace hapticd::drivers::evdev
