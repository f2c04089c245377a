// The reference Logitech wheel (logitech_wheel.h) on the raw gadget in the kernel test machine:
// the kernel's own Logitech driver binds to it (hid-lg, force feedback by hid-lgff through
// ff-memless), and hapticd's evdev driver meets it as /dev/input/eventN. First what an
// FF_CONSTANT update becomes on the wheel's wire and when (written by this test, as any
// program would, straight through EVIOCSFF); then hapticd rendering the wall through it.
#include <dirent.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hapticd_process.h"
#include "hid_support.h"
#include "logitech_wheel.h"
#include "reference_clock.h"
#include "rt_syscalls.h"

namespace hapticd::reference {
namespace {

// The /dev/input/eventN with this uniq (the USB serial) that offers FF_CONSTANT.
int open_wheel(const std::string& uniq) {
  DIR* dir = ::opendir("/dev/input");
  if (dir == nullptr) return -1;
  int found = -1;
  while (const dirent* e = ::readdir(dir)) {
    if (std::strncmp(e->d_name, "event", 5) != 0) continue;
    const int fd = ::open((std::string("/dev/input/") + e->d_name).c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) continue;
    char text[64] = {};
    unsigned long ff[4] = {};
    if (ioctl(fd, EVIOCGUNIQ(sizeof text - 1), text) >= 0 && uniq == text &&
        ioctl(fd, EVIOCGBIT(EV_FF, sizeof ff), ff) >= 0 &&
        ((ff[FF_CONSTANT / 64] >> FF_CONSTANT % 64) & 1)) {
      found = fd;
      break;
    }
    ::close(fd);
  }
  ::closedir(dir);
  return found;
}

struct Wheel {
  explicit Wheel(LogitechWheelOptions o = {})
      : serial(o.serial), wheel(std::make_unique<LogitechWheel>(o)) {
    EXPECT_TRUE(wait_until([&] { return (fd = open_wheel(serial)) >= 0; }))
        << "no /dev/input/eventN with FF_CONSTANT: hid-lg did not bind (see dmesg)";
  }
  ~Wheel() {
    if (fd >= 0) ::close(fd);
    EXPECT_EQ(wheel->error(), "");
    wheel.reset();
  }
  // The constant-force reports the wheel took after `after_ns`, oldest first, each as X - centre
  // (lgff: 0x51 0x08 X, centre 0x7f; lg4ff: 0x11 0x08 X, centre 0x80, or 0x13 for none) and
  // when it came.
  std::vector<std::pair<int, std::int64_t>> xs_after(std::int64_t after_ns) const {
    std::vector<std::pair<int, std::int64_t>> out;
    for (const auto& c : wheel->commands()) {
      const auto& b = c.bytes;
      if (c.time_ns <= after_ns) continue;
      if (b.size() >= 3 && b[0] == 0x51 && b[1] == 0x08) out.emplace_back(b[2] - 0x7f, c.time_ns);
      if (b.size() >= 3 && b[0] == 0x11 && b[1] == 0x08) out.emplace_back(b[2] - 0x80, c.time_ns);
      if (!b.empty() && b[0] == 0x13) out.emplace_back(0, c.time_ns);
    }
    return out;
  }
  // The last of them all ({-1000, 0} before the first).
  std::pair<int, std::int64_t> last_x() const {
    const auto xs = xs_after(0);
    return xs.empty() ? std::pair<int, std::int64_t>{-1000, 0} : xs.back();
  }
  std::string serial;
  std::unique_ptr<LogitechWheel> wheel;
  int fd = -1;
};

void update(int fd, ff_effect& e, int level) {
  e.u.constant.level = static_cast<__s16>(level);
  ASSERT_EQ(ioctl(fd, EVIOCSFF, &e), 0) << std::strerror(errno);
}

// Each level, uploaded alone and played, becomes one X byte; and the time from the EVIOCSFF to
// the report at the wheel is ff-memless's timer (the next jiffy: 4 ms at Debian's HZ 250) and
// the USB transfer.
TEST(LogitechWheel, WhatAConstantForceBecomesOnTheWire) {
  Wheel w;
  ASSERT_GE(w.fd, 0);
  ff_effect e{};
  e.type = FF_CONSTANT;
  e.id = -1;
  // "90 deg -> 0x4000 (left)" (<linux/input.h>): ml_combine_effects makes X = sin(90) *
  // level, above the centre for a positive level, which turns the wheel left, toward -X.
  e.direction = 0x4000;
  ASSERT_EQ(ioctl(w.fd, EVIOCSFF, &e), 0) << std::strerror(errno);
  input_event play{};
  play.type = EV_FF;
  play.code = static_cast<__u16>(e.id);
  play.value = 1;
  ASSERT_EQ(::write(w.fd, &play, sizeof play), static_cast<ssize_t>(sizeof play));
  std::vector<double> delays_ms;
  int previous = 0;  // the X the play sent: the zero level's
  int again = 0;
  std::cout << "logitech: level -> X - centre:";
  for (int level : {0x7fff, 0x4000, 0x2000, 0x0100, 0x0080, 0, -0x0100, -0x4000, -0x7fff}) {
    std::int64_t sent = now_ns();
    update(w.fd, e, level);
    // A report with the level before's X can still come after this upload: seen once in a
    // Debian 12 run (0x2000 met 0x4000's X first, all reports within 4 ms), whether the
    // wheel's thread, stalled by the emulator, took it late or the kernel sent it twice. This
    // level's report is the first after the upload that carries its X; a level that never
    // becomes its X fails here, and nothing may follow it but its own X.
    const int want = level >> 8;  // the memless core keeps the level's top 8 bits
    const auto is_want = [&](const std::pair<int, std::int64_t>& r) { return r.first == want; };
    std::vector<std::pair<int, std::int64_t>> seen;
    const auto has_want = [&] {
      seen = w.xs_after(sent);
      return std::any_of(seen.begin(), seen.end(), is_want);
    };
    // The kernel's own race: ml_ff_upload (ff-memless.c) restarts a playing effect's timer at
    // the current jiffy and returns, and only then does input_ff_upload (ff-core.c) store the
    // new effect; a timer tick in between plays the stored one, the level before, and nothing
    // plays again. Seen once in a run of this binary (0x7fff met only the play's X 0). Any program
    // that uploads once is left with the old force; hapticd's evdev driver uploads every tick
    // (drivers/evdev/update_thread.cpp), as this does once more: only the level before's X,
    // and the new level then, passes.
    if (!wait_until(has_want, std::chrono::milliseconds(300)) &&
        std::all_of(seen.begin(), seen.end(), [&](const auto& r) { return r.first == previous; })) {
      ++again;
      sent = now_ns();
      update(w.fd, e, level);
    }
    if (!wait_until(has_want, std::chrono::seconds(2))) {
      std::string xs;
      for (const auto& r : seen) xs += " " + std::to_string(r.first);
      ADD_FAILURE() << "level " << level << " never reached the wheel as X - centre " << want
                    << "; the reports after its upload:" << (xs.empty() ? " none" : xs);
      continue;
    }
    previous = want;
    const auto at = std::find_if(seen.begin(), seen.end(), is_want)->second;
    delays_ms.push_back((at - sent) * 1e-6);
    std::cout << " " << level << "->" << want;
    EXPECT_EQ(w.last_x().first, want) << "nothing after it but its own X";
    if (level == 0x7fff) {
      EXPECT_LT(w.wheel->torque(), 0.0) << "a positive level at 0x4000: toward -X";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::cout << "\n";
  std::cout << "logitech: " << again << " of 9 levels uploaded again (played before stored)\n";
  ASSERT_FALSE(delays_ms.empty());
  std::sort(delays_ms.begin(), delays_ms.end());
  std::cout << "logitech: EVIOCSFF to the wheel's report: median "
            << delays_ms[delays_ms.size() / 2] << " ms, max " << delays_ms.back() << " ms\n";
  // A hundred updates of one level at 100 Hz: ff-memless plays the effect again at each
  // upload, changed or not (hid-pidff sends nothing for an unchanged level).
  const std::size_t before_same = w.wheel->commands().size();
  const std::int64_t start_same = now_ns();
  for (int i = 0; i < 100; ++i) {
    update(w.fd, e, 0x3000);
    std::this_thread::sleep_until(std::chrono::steady_clock::time_point(
        std::chrono::nanoseconds(start_same + (i + 1) * 10'000'000LL)));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::size_t same = w.wheel->commands().size() - before_same;
  std::cout << "logitech: 100 updates of one level at 100 Hz reached the wheel as " << same
            << " reports\n";
  EXPECT_GT(same, 90u);
  // A thousand updates a second for a second: the timer passes at most one a jiffy.
  const std::size_t before = w.wheel->commands().size();
  const std::int64_t start = now_ns();
  for (int i = 0; i < 1000; ++i) {
    update(w.fd, e, (i % 2 == 0) ? 0x4000 : 0x3000);
    std::this_thread::sleep_until(std::chrono::steady_clock::time_point(
        std::chrono::nanoseconds(start + (i + 1) * 1'000'000LL)));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::size_t reports = w.wheel->commands().size() - before;
  std::cout << "logitech: 1000 updates in " << (now_ns() - start) * 1e-9
            << " s reached the wheel as " << reports << " reports\n";
  EXPECT_LT(reports, 400u) << "ff-memless plays at most one update per jiffy";
  play.value = 0;
  ASSERT_EQ(::write(w.fd, &play, sizeof play), static_cast<ssize_t>(sizeof play));
  EXPECT_TRUE(wait_until([&] { return w.last_x().first == 0; }, std::chrono::seconds(2)))
      << "stopped: the centre, no force";
}

constexpr double kStiffness = 5.0;  // N m/rad: at 100 Hz the gate allows up to 9 with b 0.05
// N m: three quarters of the wheel's full torque, 96 of the 127 steps of its 8-bit force,
// so the step's resolution (1 %) is inside the test's 2 %.
constexpr double kPush = 1.5;

// hapticd with config/evdev.yaml on the wheel: ff_driver memless at 100 Hz (below the kernel's
// 250 Hz timer), its 270 degrees and 2 N m. The emulated machine's thresholds: overruns and
// late updates (an EVIOCSFF through ff-memless takes it 3 ms, up to 14, above the 5 ms that
// update_latency_ms 0 covers) are counted, not faulted.
std::vector<std::string> wheel_sets(const std::string& serial) {
  return {"loop.rate_hz=100",
          "loop.overrun_fault_streak=1000",
          "safety.direction_check.max_latency_ms=300",
          "device.evdev.late_update_fault=1000",
          "safety.stale_fault_ticks=50",
          "device.mass=0.05",
          "device.damping=0.05",
          "device.max_force=2",
          "wall.stiffness=" + std::to_string(kStiffness),
          "wall.damping=0",
          "device.evdev.select={vendor_id: 0x046d, product_id: 0xc293, uniq: \"" + serial + "\"}",
          "device.evdev.axis={code: ABS_X, min: -2.356194, max: 2.356194}",
          "device.evdev.force_full_scale=2",
          "device.evdev.ff_driver=memless"};
}

TEST(LogitechWheel, ThroughTheKernelsLogitechDriverTheWallHoldsTheHand) {
  Wheel w;
  ASSERT_GE(w.fd, 0);
  ::close(w.fd);  // hapticd opens it itself
  w.fd = -1;
  double x_rest = 0.0, torque_rest = 0.0;
  std::size_t reports = 0;
  int x_byte = -1000;
  // Under strace the loop skips periods, and the direction check starts its push again after
  // each (docs/devices.md): never done within its time-out, it is off here (the direction
  // through hid-lg4ff is WhatAConstantForceBecomesOnTheWire's, the shipped configuration's
  // check OpenFfboardEvdev's), not what is measured.
  std::vector<std::string> sets = wheel_sets(w.serial);
  sets.push_back("safety.direction_check.mode=off");
  const HapticdRun r = run_hapticd(
      shipped("evdev.yaml"), sets, {"--duration", "7"},
      [&](pid_t) {
        // The effect plays: the wheel has had its first constant-force report.
        ASSERT_TRUE(wait_until([&] { return w.last_x().second > 0; })) << "output never enabled";
        w.wheel->axis().hand(kPush, 1.0);
        std::this_thread::sleep_for(std::chrono::seconds(3));
        const std::size_t before = w.wheel->commands().size();
        std::this_thread::sleep_for(std::chrono::seconds(1));
        reports = w.wheel->commands().size() - before;
        x_rest = w.wheel->axis().position();
        torque_rest = w.wheel->torque();
        x_byte = w.last_x().first;
      },
      strace_to("/tmp/hapticd-logitech-strace"));
  ASSERT_EQ(r.status, 0) << r.faults() << "\n" << r.log;
  EXPECT_EQ(r.faults(), "[]");
  // The loop's thread under strace (rt_syscalls.h): what it asks of the kernel each tick. The
  // update (EVIOCSFF) is the driver's update thread's.
  TickCalls calls = tick_calls("/tmp/hapticd-logitech-strace");
  std::cout << "logitech, the loop's thread: " << describe(calls) << "\n";
  EXPECT_EQ(calls.per_tick.count("ioctl EVIOCSFF"), 0u) << "not on the loop's thread";
  // At most one a tick: under strace the update thread falls behind, and the newest level wins
  // (0.53 a tick in the emulated machine).
  EXPECT_GT(calls.sff_elsewhere_per_tick, 0.2);
  EXPECT_LE(calls.sff_elsewhere_per_tick, 1.05);
  EXPECT_NEAR(x_rest, kPush / kStiffness, 0.02 * kPush / kStiffness) << "resting penetration";
  EXPECT_NEAR(torque_rest, -kPush, 0.02 * kPush) << "the wall's torque at rest";
  // The shipped direction 270 (0xC000, "right") turns the wall's negative level into X above
  // the centre: the wheel turns left, toward -X, out of the wall.
  EXPECT_GT(x_byte, 0);
  std::cout << "logitech: resting penetration " << x_rest << " rad (F/K " << kPush / kStiffness
            << "), torque " << torque_rest << " N m as X - centre " << x_byte << "; " << reports
            << " reports in the 100 ticks of a second at rest\n";

  EXPECT_EQ(w.wheel->torque(), 0.0) << "stopped at the end";
}

}  // namespace
}  // namespace hapticd::reference
