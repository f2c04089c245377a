// The simulated PID device (sim/peers/hid, pid_reference_descriptor) against Linux's own PID
// host, hid-pidff, in the kernel test machine: as a USB device on the raw gadget, usbhid binds
// hid-pidff to it, which needs every report its PID host requires (PID Pool, Set Envelope,
// Block Load read through GET_REPORT, Device Control...) before it offers force feedback
// through evdev. An FF_CONSTANT effect uploaded (EVIOCSFF) and played there must make the
// simulated device apply the force the effect asks for: something independent of hapticd's
// codecs confirms that the device behaves as a PID device.
#include <dirent.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cmath>
#include <cstring>

#include "kernel_rig.h"

namespace hapticd::drivers::hid {
namespace {

using namespace testing;

bool has_bit(const unsigned long* bits, int bit) {
  constexpr int kPerLong = 8 * sizeof(unsigned long);
  return (bits[bit / kPerLong] >> (bit % kPerLong)) & 1UL;
}

// The /dev/input/eventN of the device with this serial (its uniq) that offers FF_CONSTANT.
int open_force_feedback(const std::string& serial) {
  DIR* dir = ::opendir("/dev/input");
  if (dir == nullptr) return -1;
  int found = -1;
  while (const dirent* e = ::readdir(dir)) {
    if (std::strncmp(e->d_name, "event", 5) != 0) continue;
    const std::string path = std::string("/dev/input/") + e->d_name;
    const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) continue;
    char uniq[64] = {};
    unsigned long ff[(FF_CNT + 8 * sizeof(unsigned long) - 1) / (8 * sizeof(unsigned long))] = {};
    if (ioctl(fd, EVIOCGUNIQ(sizeof uniq - 1), uniq) >= 0 && serial == uniq &&
        ioctl(fd, EVIOCGBIT(EV_FF, sizeof ff), ff) >= 0 && has_bit(ff, FF_CONSTANT)) {
      found = fd;
      break;
    }
    ::close(fd);
  }
  ::closedir(dir);
  return found;
}

void play(int fd, int effect, int value) {
  input_event ev{};
  ev.type = EV_FF;
  ev.code = static_cast<__u16>(effect);
  ev.value = value;
  ASSERT_EQ(::write(fd, &ev, sizeof ev), static_cast<ssize_t>(sizeof ev)) << std::strerror(errno);
}

TEST(HidPidff, TheKernelsPidDriverBindsAndItsConstantForceMovesTheSimulatedDevice) {
  const std::vector<std::string> sets = sets_for("hidraw");
  const config::Config cfg = load_example("hid-pid.yaml", sets);
  auto peer = std::make_unique<KernelPeer>(cfg, "/dev/raw-gadget");
  KernelPeer& device = *peer;
  ASSERT_TRUE(wait_listed(true));
  int fd = -1;
  ASSERT_TRUE(KernelPeer::wait_for([&] { return (fd = open_force_feedback(kKernelSerial)) >= 0; }))
      << "no /dev/input/eventN with FF_CONSTANT: hid-pidff did not bind (see dmesg)";

  // Half of full scale toward +X, playing until stopped: direction 0xC000, "270 deg -> 0xC000
  // (right)" in <linux/input.h>. hid-pidff rescales it onto the PID Direction
  // (pidff_set_effect_report: pidff_rescale(effect->direction, 0xffff, ...), 26999 of
  // 0..35999), which the simulated device renders as OpenFFBoard does: -sin(direction), +X.
  ff_effect effect{};
  effect.type = FF_CONSTANT;
  effect.id = -1;
  effect.direction = 0xC000;
  effect.u.constant.level = 0x4000;
  ASSERT_EQ(ioctl(fd, EVIOCSFF, &effect), 0) << std::strerror(errno);
  EXPECT_EQ(device.peer->applied_force(), 0.0) << "uploaded, not yet played";
  play(fd, effect.id, 1);
  const double full_scale = settings_of(cfg)->pid.force_full_scale;
  const double expected = 0.5 * full_scale;  // 0x4000 / 0x7fff of the magnitude's range
  EXPECT_TRUE(KernelPeer::wait_for(
      [&] { return std::abs(device.peer->applied_force() - expected) < 0.01 * expected; },
      std::chrono::seconds(5)))
      << "applied " << device.peer->applied_force() << " N, expected " << expected << " N";
  // "90 deg -> 0x4000 (left)": the same level toward -X (hid-pidff sends Set Effect again for
  // the changed direction).
  effect.direction = 0x4000;
  ASSERT_EQ(ioctl(fd, EVIOCSFF, &effect), 0) << std::strerror(errno);
  EXPECT_TRUE(KernelPeer::wait_for(
      [&] { return std::abs(device.peer->applied_force() + expected) < 0.01 * expected; },
      std::chrono::seconds(5)))
      << "applied " << device.peer->applied_force() << " N, expected " << -expected << " N";
  play(fd, effect.id, 0);
  EXPECT_TRUE(KernelPeer::wait_for([&] { return device.peer->applied_force() == 0.0; },
                                   std::chrono::seconds(5)))
      << "stopped, yet " << device.peer->applied_force() << " N";
  EXPECT_EQ(ioctl(fd, EVIOCRMFF, effect.id), 0) << std::strerror(errno);
  ::close(fd);
  peer.reset();  // unplugged: the next test's device must not be mistaken for this one
  EXPECT_TRUE(wait_listed(false));
}

}  // namespace
}  // namespace hapticd::drivers::hid
