// The kernel tests' rig around the reference Falcon (falcon_rig.h).
#include "falcon_rig.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "falcon_firmware.h"

namespace hapticd::reference::falcon {

using namespace std::chrono_literals;

std::string image_file() {
  const std::string path = "/tmp/hapticd-kt-falcon-image.bin";
  std::ofstream out(path, std::ios::binary);
  for (int i = 0; i < 7914; ++i) out.put(static_cast<char>((i * 131 + 17) >> 1));
  return path;
}

bool plugged_in(const RawUsbFtdi& d) {
  // The host configured this device (not a stale entry of the last one, still going).
  return wait_until([&] { return d.configured() && listed_in_sysfs(); });
}

std::vector<std::string> reference_sets() {
  return {"device.falcon.firmware=" + image_file(), std::string("device.falcon.serial=") + kSerial};
}

void print_log_end(const std::string& log, int ticks) {
  const std::string cmd =
      std::string(HAPTICD_BINARY) + " export " + log + " | tail -" + std::to_string(ticks) + " >&2";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
}

Hand::Hand(RawUsbFtdi& d) : d_(d), t_([this] { run(); }) {}

Hand::~Hand() {
  stop_ = true;
  t_.join();
}

void Hand::set(const Vec3& f, const Vec3& centre, double k, double b) {
  const std::lock_guard l(m_);
  f_ = f;
  centre_ = centre;
  k_ = k;
  b_ = b;
}

void Hand::run() {
  while (!stop_) {
    Vec3 f, c;
    double k = 0, b = 0;
    {
      const std::lock_guard l(m_);
      f = f_, c = centre_, k = k_, b = b_;
    }
    const double fn = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    d_.with_firmware([&](FalconFirmware& fw) {
      const Vec3 x = fw.mechanism().position(), v = fw.mechanism().velocity();
      Vec3 h{};
      for (int i = 0; i < 3; ++i) {
        // The spring acts only across the push (along it the push alone, so at rest F is
        // exact); the hand's damping along every axis, as a person's arm has.
        const bool along = fn > 0 && std::abs(f[i]) > 1e-9;
        h[i] = f[i] + (along ? 0.0 : k * (c[i] - x[i])) - b * v[i];
      }
      fw.mechanism().set_hand_force(h);
      return 0;
    });
    std::this_thread::sleep_for(2ms);
  }
}

bool home(RawUsbFtdi& d, Hand& hand) {
  if (!wait_until(
          [&] { return d.with_firmware([](FalconFirmware& f) { return f.homing_mode(); }); }, 60s))
    return false;
  hand.set({0, 0, 1.0}, {0, 0, 0.11}, 0);
  if (!wait_until([&] { return d.with_firmware([](FalconFirmware& f) { return f.homed(); }) == 7; },
                  20s))
    return false;
  // A soft spring back to the middle and a firm grip: the reference's plant moves only while
  // packets flow, so it resumes after hapticd enables with the speed the pull gave it, which
  // the grip takes out at once (the box ends 15 mm beyond the arms' index), then slowly back.
  hand.set({0, 0, 0}, {0, 0, 0.11}, 10.0, 20.0);
  return true;
}

bool output_on(RawUsbFtdi& d, pid_t pid) {
  return wait_until(
      [&] {
        return ended(pid) || d.with_firmware([](FalconFirmware& f) { return f.leds() == 0x2; });
      },
      30s);
}

}  // namespace hapticd::reference::falcon
