// The reference OpenFFBoard in its FFB Joystick (2 Axis) mode (openffboard.h, axes 2) on its
// own in the kernel test machine, before hapticd meets it: its two axes in the gamepad report
// and each axis' share of an effect as the firmware gives it, through hidraw.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <cmath>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "hapticd_process.h"
#include "hid_support.h"
#include "openffboard.h"
#include "openffboard_joystick.h"

namespace hapticd::reference {
namespace {

// The joystick itself, before hapticd meets it: a host writing the PID reports by hand through
// hidraw (Set Effect 1, Set Constant Force 5, Effect Operation 0x0A; Set Effect allocates the
// block and starts FFB, as HidFFB::set_effect does) and reading the gamepad report.
class HandHost {
 public:
  explicit HandHost(const std::string& serial) {
    const auto node =
        kernel_test::find_hidraw(3, OpenFfboard::kVendor, OpenFfboard::kProduct, serial);
    if (node) fd_ = ::open(node->c_str(), O_RDWR);
  }
  ~HandHost() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool open() const { return fd_ >= 0; }
  // FFB_SetEffect_t with two axes: a constant force, infinite, gain 255, then the Type
  // Specific Block Offsets the descriptor declares.
  bool set_effect(std::uint8_t block, std::uint8_t enable_axis, std::uint16_t dx,
                  std::uint16_t dy) {
    std::vector<std::uint8_t> r(22, 0);
    r[0] = 1, r[1] = block, r[2] = 1, r[11] = 255, r[13] = enable_axis;
    r[14] = dx & 0xFF, r[15] = dx >> 8, r[16] = dy & 0xFF, r[17] = dy >> 8;
    return write(r);
  }
  bool play(std::uint8_t block, std::int16_t magnitude) {
    const auto m = static_cast<std::uint16_t>(magnitude);
    return write({5, block, static_cast<std::uint8_t>(m & 0xFF),
                  static_cast<std::uint8_t>(m >> 8)}) &&
           write({0x0A, block, 1, 1});
  }
  bool stop(std::uint8_t block) { return write({0x0A, block, 3, 0}); }
  // The next gamepad report's X and Y counts.
  std::optional<std::pair<int, int>> axes() {
    std::uint8_t buf[64];
    for (int i = 0; i < 50; ++i) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 200) <= 0) continue;
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n == 25 && buf[0] == 1) {
        return std::pair{static_cast<int>(static_cast<std::int16_t>(buf[9] | buf[10] << 8)),
                         static_cast<int>(static_cast<std::int16_t>(buf[11] | buf[12] << 8))};
      }
    }
    return std::nullopt;
  }

 private:
  bool write(const std::vector<std::uint8_t>& r) {
    return ::write(fd_, r.data(), r.size()) == static_cast<ssize_t>(r.size());
  }
  int fd_ = -1;
};

// The torque the board applies for magnitude `m` with share `share`.
double torque_of(double m, double share) { return -m * share / 32767.0 * kFullScale; }

TEST(OpenFfboardXyDevice, ReportsBothAxesAndTakesEachAxisShareAsTheFirmware) {
  OpenFfboardOptions o = joystick();
  o.start_position = 0.1;
  o.start_position_y = -0.05;
  o.serial = "openffboard-xy-self";
  auto board = std::make_unique<OpenFfboard>(o);
  ASSERT_TRUE(wait_until([&] {
    return kernel_test::hid_bound(3, OpenFfboard::kVendor, OpenFfboard::kProduct, o.serial);
  }));
  ASSERT_TRUE(wait_until([&] { return board->allocated() == 0u; }, std::chrono::seconds(5)));
  HandHost host(o.serial);
  ASSERT_TRUE(host.open());
  const std::uint64_t set_effects = board->set_effect_reports();  // the kernel's probe's
  const auto xy = host.axes();
  ASSERT_TRUE(xy.has_value()) << "no gamepad report";
  const double per_count = 20.0 * M_PI / 180.0 / 32767.0;  // 40 degrees over +-32767
  EXPECT_NEAR(xy->first * per_count, 0.1, per_count) << "X";
  EXPECT_NEAR(xy->second * per_count, -0.05, per_count) << "Y";
  const auto settled = [&](double tx, double ty) {
    return wait_until(
        [&] {
          return std::abs(board->axis(0).motor() - tx) < 1e-6 &&
                 std::abs(board->axis(1).motor() - ty) < 1e-6;
        },
        std::chrono::seconds(2));
  };
  // Way C of docs/drivers/hid.md: effect 1 X only at directionX 0 (share -1), effect 2 Y only at
  // directionY 36000 (share -(36000 - 18000)/18000 = -1): each axis its own +magnitude.
  ASSERT_TRUE(host.set_effect(1, 0x01, 0, 0) && host.set_effect(2, 0x02, 0, 36000));
  ASSERT_TRUE(host.play(1, 1000) && host.play(2, -500));
  EXPECT_TRUE(settled(torque_of(1000, -1), torque_of(-500, -1)))
      << board->axis(0).motor() << " " << board->axis(1).motor();
  // Linear shares between the ends: directionX 27000 gives X +0.5; Y not enabled gives 0,
  // and effect 2 still adds its own Y.
  ASSERT_TRUE(host.set_effect(1, 0x01, 27000, 9000));
  EXPECT_TRUE(settled(torque_of(1000, 0.5), torque_of(-500, -1)));
  ASSERT_TRUE(host.stop(2));
  // Polar (Direction Enable, bit 2 with two axes): 90 degrees is all X (sin 1, -cos 0), 180
  // all Y (-cos 180 = 1); directionY unused.
  ASSERT_TRUE(host.set_effect(1, 0x04, 9000, 12345));
  EXPECT_TRUE(settled(torque_of(1000, 1), 0.0));
  ASSERT_TRUE(host.set_effect(1, 0x04, 18000, 0));
  EXPECT_TRUE(settled(torque_of(1000, std::sin(M_PI)), torque_of(1000, 1)));
  // Bit 1 is Axes Enable Y here, not Direction Enable (as it is with one axis).
  ASSERT_TRUE(host.set_effect(1, 0x02, 9000, 0));
  EXPECT_TRUE(settled(0.0, torque_of(1000, 1)));
  ASSERT_TRUE(host.stop(1));
  EXPECT_TRUE(settled(0.0, 0.0));
  EXPECT_EQ(board->set_effect_reports() - set_effects, 6u);
}

}  // namespace
}  // namespace hapticd::reference
