// hapticd's evdev driver against the reference uinput device (uinput_ff_device.h) in the kernel
// test machine: this process is the device, the kernel's uinput and evdev carry the axis and
// the force between it and `hapticd run` with config/evdev.yaml. The machine is emulated
// (TCG), so the loop runs at 100 Hz with a wall the gate allows there, as the other kernel
// tests do, and a sample may wait in the kernel's buffer while the emulator stalls: 50 ticks
// of stale data fault, not 3 (tests/hid/kernel_rig.h says the same of the HID tests). A hand pushes
// the axis into the wall: it must come to rest where the wall's spring balances the push, F/K,
// within 2 %. Each fault must end with zero force and its cause named; a SIGKILL too, by the kernel
// itself (it erases a closed node's effects).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <regex>

#include "hapticd_process.h"
#include "rt_syscalls.h"
#include "uinput_ff_device.h"

namespace hapticd::reference {
namespace {

constexpr double kStiffness = 250.0;  // N/m: at 100 Hz the gate allows it with b 2
constexpr double kPush = 1.0;         // N: the hand's steady push into the wall
constexpr double kHandDamping = 5.0;  // N s/m
const std::string kName = "hapticd reference uinput FF device";

std::vector<std::string> sets(std::vector<std::string> more = {}) {
  std::vector<std::string> s = {"loop.rate_hz=100",
                                "loop.overrun_fault_streak=1000",
                                "safety.direction_check.max_latency_ms=300",
                                "safety.stale_fault_ticks=50",
                                "wall.stiffness=" + std::to_string(kStiffness),
                                "wall.damping=0.2",
                                "device.evdev.select={name: \"" + kName + "\"}",
                                "device.evdev.ff_driver=uinput",
                                "device.evdev.poll_interval_ms=",
                                "device.evdev.autocenter=0.3"};
  s.insert(s.end(), more.begin(), more.end());
  return s;
}

HapticdRun run(const std::vector<std::string>& set, double seconds,
               const std::function<void(pid_t)>& during = {}) {
  return run_hapticd(shipped("evdev.yaml"), set, {"--duration", std::to_string(seconds)}, during);
}

// The device as the emulated machine can carry it beside hapticd: its own loop at 250 Hz.
UinputFfOptions guest_device() {
  UinputFfOptions o;
  o.rate_hz = 250.0;
  return o;
}

// The device plugged in, 10 mm outside the wall.
struct Rig {
  Rig() : device(guest_device()) {}
  // Once hapticd plays its effect, a hand pushes the axis into the wall, and the wall pushes
  // back.
  bool pushed() {
    if (!wait_until([&] { return device.playing(); })) return false;
    std::this_thread::sleep_for(std::chrono::seconds(1));  // the direction check, at rest
    device.hand(kPush, kHandDamping);
    return wait_until([&] { return device.force() < -0.2; });
  }
  UinputFfDevice device;
};

TEST(EvdevUinput, TheWallHoldsTheHandAtForceOverStiffness) {
  Rig rig;
  double at_rest = 0.0;
  int autocenter_running = -1;
  const HapticdRun h = run(sets(), 4.0, [&](pid_t) {
    ASSERT_TRUE(rig.pushed()) << "the wall never pushed";
    std::this_thread::sleep_for(std::chrono::milliseconds(2500));
    at_rest = rig.device.position();
    autocenter_running = rig.device.autocenter();
  });
  ASSERT_EQ(h.status, 0) << h.log;
  EXPECT_EQ(h.faults(), "[]");
  const double expected = kPush / kStiffness;
  EXPECT_NEAR(at_rest, expected, 0.02 * expected)
      << "at rest " << at_rest * 1e3 << " mm, F/K " << expected * 1e3 << " mm";
  std::cout << "uinput: at rest " << at_rest * 1e3 << " mm in the wall, F/K " << expected * 1e3
            << " mm\n";
  EXPECT_EQ(autocenter_running, 0) << "autocenter off while hapticd renders";
  EXPECT_EQ(rig.device.autocenter(), std::lround(0.3 * 0xFFFF)) << "and back after";
  EXPECT_FALSE(rig.device.playing());
  EXPECT_EQ(rig.device.force(), 0.0);
  EXPECT_EQ(rig.device.effects_held(), 0) << "the effect is erased at disable";
}

// What reaches the device per tick: every update is an EVIOCSFF that returns only once this
// process took it, so each tick's level arrives within the tick, one upload per tick. And what
// the loop's thread asks of the kernel each tick, under strace: the events read (libevdev: one
// read(2), one more that finds the buffer empty when an event came, and now and then a third
// when an event lands between the two) and that EVIOCSFF.
// The guest's clock has no vDSO path under the emulator (its clocksource is the HPET, not the
// TSC), so its clock_gettime calls show as system calls here; on a TSC host they do not.
TEST(EvdevUinput, EveryTickUploadsTheLevelOnceAndTheLoopThreadDoesLittleElse) {
  Rig rig;
  const std::string trace = "/tmp/hapticd-uinput-strace";
  std::vector<std::string> args = {"run", "--config", shipped("evdev.yaml"), "--duration", "3"};
  for (const std::string& s : sets()) args.insert(args.end(), {"--set", s});
  const HapticdRun h = run_hapticd(
      args, [&](pid_t) { ASSERT_TRUE(rig.pushed()); }, strace_to(trace));
  ASSERT_EQ(h.status, 0) << h.log;
  const std::vector<Upload> ups = rig.device.uploads();
  ASSERT_GT(ups.size(), 100u);
  const auto ticks = h.summary["ticks"].get<std::uint64_t>();
  // The upload at configure, one a tick, and the zero of the disable.
  EXPECT_NEAR(static_cast<double>(ups.size()), static_cast<double>(ticks), 0.02 * ticks + 3);
  std::vector<double> gaps;
  for (std::size_t i = 2; i + 1 < ups.size(); ++i) {
    gaps.push_back((ups[i].time_ns - ups[i - 1].time_ns) * 1e-6);
  }
  std::sort(gaps.begin(), gaps.end());
  const double p50 = gaps[gaps.size() / 2];
  EXPECT_NEAR(p50, 10.0, 1.0) << "one upload a 10 ms tick";
  std::cout << "uinput: " << ups.size() << " uploads over " << ticks << " ticks; interval p50 "
            << p50 << " ms, max " << gaps.back() << " ms\n";
  TickCalls t = tick_calls(trace);
  std::cout << "uinput, the loop's thread: " << describe(t) << "\n";
  ASSERT_GT(t.ticks, 100);
  EXPECT_NEAR(t.per_tick["ioctl EVIOCSFF"], 1.0, 0.02);
  EXPECT_LE(t.per_tick["read"], 2.5) << "two, a third when an event lands between them";
  for (const auto& [name, n] : t.per_tick) {
    EXPECT_TRUE(name == "read" || name == "ioctl EVIOCSFF" || name == "clock_gettime")
        << name << " " << n << " a tick";
  }
}

TEST(EvdevUinput, AnUnpluggedDeviceIsATransportFaultNamed) {
  Rig rig;
  const HapticdRun h = run(sets(), 30.0, [&](pid_t) {
    ASSERT_TRUE(rig.pushed());
    rig.device.unplug();
  });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_TRUE(std::regex_search(h.faults(), std::regex("the device is gone"))) << h.faults();
  EXPECT_EQ(rig.device.force(), 0.0);
}

TEST(EvdevUinput, AnAxisThatFallsSilentUnderForceIsStaleData) {
  Rig rig;
  const HapticdRun h = run(sets({"device.evdev.liveness_ms=300"}), 30.0, [&](pid_t) {
    ASSERT_TRUE(rig.pushed());
    rig.device.go_silent();
  });
  EXPECT_EQ(h.status, 1) << h.log;
  EXPECT_TRUE(std::regex_search(h.faults(), std::regex("stale"))) << h.faults();
  EXPECT_TRUE(wait_until([&] { return rig.device.force() == 0.0 && !rig.device.playing(); },
                         std::chrono::seconds(2)))
      << "force " << rig.device.force();
  EXPECT_GT(h.summary["counters"]["evdev"]["silent_ticks"].get<std::uint64_t>(), 0u);
}

// Another process holding the device grabbed: hapticd cannot have it alone, so it never
// enables output; and while hapticd holds it, another's grab is refused.
TEST(EvdevUinput, ASecondProcessGrabbingIsRefusedEitherWay) {
  Rig rig;
  {
    const int fd = ::open(rig.device.event_path().c_str(), O_RDONLY | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(ioctl(fd, EVIOCGRAB, 1), 0);
    const HapticdRun h = run(sets(), 5.0);
    ::close(fd);
    EXPECT_EQ(h.status, 4) << h.log;
    EXPECT_TRUE(std::regex_search(h.log, std::regex("another process has grabbed"))) << h.log;
    EXPECT_FALSE(rig.device.playing());
    EXPECT_EQ(rig.device.force(), 0.0);
  }
  int grab_errno = 0;
  const HapticdRun h = run(sets(), 3.0, [&](pid_t) {
    ASSERT_TRUE(rig.pushed());
    const int fd = ::open(rig.device.event_path().c_str(), O_RDONLY | O_CLOEXEC);
    grab_errno = ioctl(fd, EVIOCGRAB, 1) == 0 ? 0 : errno;
    ::close(fd);
  });
  EXPECT_EQ(grab_errno, EBUSY) << "hapticd holds the device while output is on";
  EXPECT_EQ(h.status, 0) << h.log;
}

// `hapticd identify` through the same device, held free: it drives the axis with a multisine
// force and fits the device's own mass and damping (0.1 kg, 2 N s/m in the reference). Measured
// once: 0.091 kg and 1.95 N s/m.
TEST(EvdevUinput, IdentifyFindsTheDevicesMassAndDamping) {
  Rig rig;
  std::vector<std::string> args = {"identify",
                                   "--json",
                                   "--config",
                                   shipped("evdev.yaml"),
                                   "--yes-the-device-is-free",
                                   "--duration",
                                   "4",
                                   "--amplitude",
                                   "1",
                                   "--f-low",
                                   "0.5",
                                   "--f-high",
                                   "10"};
  for (const std::string& s : sets()) args.insert(args.end(), {"--set", s});
  args.insert(args.begin(), HAPTICD_BINARY);
  const std::string out = "/tmp/hapticd-identify.json";
  std::string command;
  for (const std::string& a : args) command += "'" + a + "' ";
  const int status = std::system((command + "> " + out + " 2>/tmp/hapticd-identify.err").c_str());
  ASSERT_EQ(WEXITSTATUS(status), 0) << std::ifstream("/tmp/hapticd-identify.err").rdbuf();
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(out), nullptr, false);
  ASSERT_TRUE(j.is_object());
  std::cout << "uinput, identify: " << j.dump() << "\n";
  // The reference integrates its axis in real time at 250 Hz (semi-implicit Euler), the fit
  // assumes the exact sampled plant: within 15 % and 10 %.
  EXPECT_NEAR(j["mass"].get<double>(), 0.1, 0.015);
  EXPECT_NEAR(j["damping"].get<double>(), 2.0, 0.2);
  EXPECT_FALSE(rig.device.playing());
}

// SIGKILL leaves hapticd no chance to disable: the kernel erases the effects a closed node
// made, so the device stops.
TEST(EvdevUinput, AfterSigkillTheKernelErasesTheEffect) {
  Rig rig;
  const HapticdRun h = run(sets(), 30.0, [&](pid_t pid) {
    ASSERT_TRUE(rig.pushed());
    ::kill(pid, SIGKILL);
  });
  EXPECT_EQ(h.status, 128 + SIGKILL);
  EXPECT_TRUE(wait_until([&] { return rig.device.effects_held() == 0; }, std::chrono::seconds(2)));
  EXPECT_EQ(rig.device.force(), 0.0);
}

}  // namespace
}  // namespace hapticd::reference
