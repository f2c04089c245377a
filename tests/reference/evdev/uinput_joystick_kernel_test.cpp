// hapticd's evdev driver with two axes against the reference uinput joystick
// (uinput_ff_joystick.h) in the kernel test machine: this process is the joystick, the kernel's
// uinput and evdev carry its ABS_X and ABS_Y and the force between it and `hapticd run` with
// config/evdev-joystick.yaml, as a user runs it. A hand pushes the grip along the diagonal into
// the example's wall, whose normal (1, 1) is neither axis: the grip must come to rest where the
// wall's spring balances the push, F/K along the normal, within 2 %, with the one effect whose
// direction follows the force and with one effect per axis; what reached the device each tick
// is counted for both. Unplugging, silence, a value far out of range and a flood of garbage
// (the kernel's buffer overflowing: SYN_DROPPED) each end the run with zero force on both axes
// and the cause named. The machine is emulated (TCG): the loop runs at 100 Hz with a wall the
// gate allows there, and counts the emulator's stalls rather than fault on them, as
// uinput_kernel_test.cpp does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <regex>

#include "hapticd_process.h"
#include "reference_clock.h"
#include "rt_syscalls.h"
#include "uinput_ff_joystick.h"

namespace hapticd::reference {
namespace {

constexpr double kJoyStiffness = 250.0;  // N/m along the normal: the gate allows it at 100 Hz
constexpr double kJoyPush = 1.0;         // N: the hand's steady push along the diagonal
constexpr double kJoyHandDamping = 5.0;  // N s/m
const double kJoyDiagonal = 1.0 / std::sqrt(2.0);

std::vector<std::string> joy_sets(std::vector<std::string> more = {}) {
  std::vector<std::string> s = {"loop.rate_hz=100",
                                "loop.overrun_fault_streak=1000",
                                "safety.stale_fault_ticks=100",
                                "device.evdev.late_update_fault=1000",
                                "walls[0].stiffness=" + std::to_string(kJoyStiffness),
                                "walls[0].damping=0.2"};
  s.insert(s.end(), more.begin(), more.end());
  return s;
}

HapticdRun joy_run(const std::vector<std::string>& set, double seconds,
                   const std::function<void(pid_t)>& during = {}) {
  return run_hapticd(shipped("evdev-joystick.yaml"), set, {"--duration", std::to_string(seconds)},
                     during);
}

// How deep the grip is in the example's wall: its face through (0.01, 0.01), normal (1, 1).
double joy_depth(const UinputFfJoystick& j) {
  return kJoyDiagonal * (j.position(0) - 0.01) + kJoyDiagonal * (j.position(1) - 0.01);
}

// Once hapticd plays its effect (the direction check is off with two axes: the example says
// why), a hand pushes the grip along the diagonal into the wall, and the wall pushes back on
// both axes.
bool joy_pushed(UinputFfJoystick& j) {
  if (!wait_until([&] { return j.playing(); })) return false;
  j.hand(kJoyPush * kJoyDiagonal, kJoyPush * kJoyDiagonal, kJoyHandDamping);
  return wait_until([&] { return j.force(0) < -0.1 && j.force(1) < -0.1; });
}

struct PerTick {
  double uploads = 0.0;     // uploads a tick
  double directions = 0.0;  // uploads that changed an effect's direction, a tick
  // The reports hid-pidff would send for the same uploads: pidff_upload_effect sends a Set
  // Effect report when pidff_needs_set_effect (the direction among its fields) and a Set
  // Constant Force report when pidff_needs_set_constant (the level), per effect, against the
  // effect as it was (torvalds/linux drivers/hid/usbhid/hid-pidff.c).
  double pidff_reports = 0.0;
};

// The uploads that reached the device from `from_ns` to `to_ns`, over the loop's ticks then
// (100 Hz); the first of each effect (its creation at configure) is not an update.
PerTick per_tick(const std::vector<JoystickUpload>& ups, std::int64_t from_ns, std::int64_t to_ns) {
  PerTick p;
  std::map<int, JoystickUpload> last;
  for (const JoystickUpload& u : ups) {
    if (u.time_ns > to_ns) break;
    if (u.time_ns < from_ns) {
      last[u.id] = u;
      continue;
    }
    p.uploads += 1.0;
    const auto it = last.find(u.id);
    if (it != last.end()) {
      const bool turned = it->second.direction != u.direction;
      p.directions += turned ? 1.0 : 0.0;
      p.pidff_reports += (turned ? 1.0 : 0.0) + (it->second.level != u.level ? 1.0 : 0.0);
    }
    last[u.id] = u;
  }
  const double t = static_cast<double>(to_ns - from_ns) * 1e-9 * 100.0;
  return {p.uploads / t, p.directions / t, p.pidff_reports / t};
}

class EvdevJoystick : public ::testing::TestWithParam<const char*> {};

TEST_P(EvdevJoystick, TheWallHoldsTheHandAtForceOverStiffnessAlongTheDiagonal) {
  UinputFfJoystick joystick;
  double at_rest = 0.0, x = 0.0, y = 0.0;
  std::int64_t rest_from = 0, rest_to = 0;  // a window at rest in the wall
  const HapticdRun h =
      joy_run(joy_sets({std::string("device.evdev.effect=") + GetParam()}), 6.0, [&](pid_t) {
        ASSERT_TRUE(joy_pushed(joystick)) << "the wall never pushed";
        std::this_thread::sleep_for(std::chrono::milliseconds(1000));
        rest_from = now_ns();
        std::this_thread::sleep_for(std::chrono::milliseconds(1500));
        rest_to = now_ns();
        at_rest = joy_depth(joystick);
        x = joystick.position(0);
        y = joystick.position(1);
      });
  ASSERT_EQ(h.status, 0) << h.log;
  EXPECT_EQ(h.faults(), "[]");
  const double expected = kJoyPush / kJoyStiffness;
  EXPECT_NEAR(at_rest, expected, 0.02 * expected)
      << "at rest " << at_rest * 1e3 << " mm in the wall, F/K " << expected * 1e3 << " mm";
  // Along the face the wall holds nothing: x and y may part there (per_axis's two effects
  // reach the device one after the other), only the depth is the wall's.
  const auto ticks = h.summary["ticks"].get<std::uint64_t>();
  const std::vector<JoystickUpload> ups = joystick.uploads();
  const PerTick p = per_tick(ups, rest_from, rest_to);
  const nlohmann::json& c = h.summary["counters"]["evdev"];
  std::cout << "joystick, effect " << GetParam() << ": at rest " << at_rest * 1e3
            << " mm in the wall (F/K " << expected * 1e3 << " mm; x " << x * 1e3 << " mm, y "
            << y * 1e3 << " mm); " << ticks << " ticks, " << ups.size()
            << " uploads; at rest in the wall " << p.uploads
            << " uploads a tick, direction changed " << p.directions
            << " a tick, hid-pidff's reports for them " << p.pidff_reports << " a tick; counters "
            << c.dump() << "\n";
  // One EVIOCSFF a tick with one effect, two with an effect per axis: each taken or replaced
  // by the next tick's.
  const double per_update = std::string(GetParam()) == "per_axis" ? 2.0 : 1.0;
  EXPECT_NEAR(static_cast<double>(c["effect_updates"].get<std::uint64_t>() / per_update +
                                  c["updates_superseded"].get<std::uint64_t>()),
              static_cast<double>(ticks + 2), 3.0);
  EXPECT_FALSE(joystick.playing());
  EXPECT_EQ(joystick.force(0), 0.0);
  EXPECT_EQ(joystick.force(1), 0.0);
  EXPECT_EQ(joystick.effects_held(), 0) << "the effects are erased at disable";
}

INSTANTIATE_TEST_SUITE_P(Effect, EvdevJoystick, ::testing::Values("direction", "per_axis"));

// What the loop's thread asks of the kernel each tick with two axes, under strace: the events
// read and at most one futex wake; the update thread makes the EVIOCSFF (one a tick with one
// effect).
TEST(EvdevJoystickCalls, EveryTickTheLoopThreadReadsAndWakesTheUpdateThreadOnly) {
  UinputFfJoystick joystick;
  const std::string trace = "/tmp/hapticd-joystick-strace";
  std::vector<std::string> args = {"run", "--config", shipped("evdev-joystick.yaml"), "--duration",
                                   "10"};
  // strace slows every thread of hapticd (an EVIOCSFF takes milliseconds): the one-axis test's
  // headroom (10 N) keeps the wall from the runaway guard's limit meanwhile, and the run is
  // long enough for the push to meet the wall after hapticd's slower start.
  for (const std::string& s :
       joy_sets({"device.max_force=10", "device.evdev.force_full_scale=15"})) {
    args.insert(args.end(), {"--set", s});
  }
  const HapticdRun h = run_hapticd(
      args, [&](pid_t) { ASSERT_TRUE(joy_pushed(joystick)); }, strace_to(trace));
  ASSERT_EQ(h.status, 0) << h.log;
  TickCalls t = tick_calls(trace);
  std::cout << "joystick, the loop's thread: " << describe(t) << "\n";
  ASSERT_GT(t.ticks, 100);
  EXPECT_EQ(t.per_tick.count("ioctl EVIOCSFF"), 0u) << "the update thread's, not the loop's";
  EXPECT_LE(t.sff_elsewhere_per_tick, 1.05) << "one effect: at most one update a tick";
  EXPECT_LE(t.per_tick["futex"], 1.0) << "at most one wake a tick";
  for (const auto& [name, n] : t.per_tick) {
    EXPECT_TRUE(name == "read" || name == "futex" || name == "clock_gettime")
        << name << " " << n << " a tick";
  }
}

// Each fault: the run ends with exit 1 and its cause named, and the joystick feels nothing on
// either axis after.
void expect_zero_after(const UinputFfJoystick& j) {
  EXPECT_TRUE(wait_until([&] { return !j.playing(); }, std::chrono::seconds(2)));
  EXPECT_EQ(j.force(0), 0.0);
  EXPECT_EQ(j.force(1), 0.0);
}

TEST(EvdevJoystickFaults, UnpluggedIsATransportFaultNamed) {
  UinputFfJoystick joystick;
  const HapticdRun h = joy_run(joy_sets(), 30.0, [&](pid_t) {
    ASSERT_TRUE(joy_pushed(joystick));
    joystick.unplug();
  });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_TRUE(std::regex_search(h.faults(), std::regex("the device is gone"))) << h.faults();
  expect_zero_after(joystick);
}

TEST(EvdevJoystickFaults, SilentAxesUnderForceAreStaleData) {
  UinputFfJoystick joystick;
  const HapticdRun h = joy_run(joy_sets({"device.evdev.liveness_ms=300"}), 30.0, [&](pid_t) {
    ASSERT_TRUE(joy_pushed(joystick));
    joystick.go_silent();
  });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_TRUE(std::regex_search(h.faults(), std::regex("stale"))) << h.faults();
  EXPECT_GT(h.summary["counters"]["evdev"]["silent_ticks"].get<std::uint64_t>(), 0u);
  expect_zero_after(joystick);
}

// ABS_Y stuck 40 times beyond its range's end (2 m from a 50 mm stick): the kernel passes it
// on as it is, and the loop's speed check refuses the jump.
TEST(EvdevJoystickFaults, AValueFarOutOfRangeIsImpossibleEncoderData) {
  UinputFfJoystick joystick;
  const HapticdRun h = joy_run(joy_sets(), 30.0, [&](pid_t) {
    ASSERT_TRUE(joy_pushed(joystick));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    joystick.corrupt_y(40 * 32767);
  });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_TRUE(std::regex_search(h.faults(), std::regex("impossible encoder data: position jumped")))
      << h.faults();
  expect_zero_after(joystick);
}

// 5000 frames at once of values up to 40 times the range's end, then silence: more than
// evdev's buffer for a reader holds, so the kernel drops what does not fit and hapticd reads
// SYN_DROPPED (counted); libevdev then reads the kernel's state, the flood's last values, and
// the loop refuses them: its speed check, or, when the first garbage a tick reads is a pose
// within a jump of the last but outside the kinematics' workspace, the workspace check (seen
// once in the kernel test machine; which comes first depends on where the reads fall in the
// flood). (A SYN_DROPPED alone is no fault: the state read after it is the device's own,
// docs/drivers/evdev.md.)
TEST(EvdevJoystickFaults, AFloodOfGarbageOverflowsTheKernelsBufferAndFaults) {
  UinputFfJoystick joystick;
  const HapticdRun h = joy_run(joy_sets(), 30.0, [&](pid_t) {
    ASSERT_TRUE(joy_pushed(joystick));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    joystick.flood(5000, 40);
  });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_TRUE(std::regex_search(
      h.faults(), std::regex("impossible encoder data: position jumped|outside workspace")))
      << h.faults();
  std::cout << "joystick, flood: counters " << h.summary["counters"]["evdev"].dump() << "\n";
  EXPECT_GT(h.summary["counters"]["evdev"]["syn_dropped"].get<std::uint64_t>(), 0u);
  expect_zero_after(joystick);
}

}  // namespace
}  // namespace hapticd::reference
