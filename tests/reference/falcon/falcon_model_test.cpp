// The reference Falcon's model without USB (falcon_firmware.h, falcon_mechanism.h): the
// bootloader's handshake and echo as libnifalcon's host steps expect them (libnifalcon
// f7c727aa: FalconCommLibUSB.cpp setFirmwareMode/setNormalMode, FalconFirmware.cpp
// loadFirmware), the packets, and the mechanism against its own forward kinematics.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "falcon_firmware.h"
#include "falcon_mechanism.h"

namespace hapticd::reference::falcon {
namespace {

using Bytes = std::vector<std::uint8_t>;

// setFirmwareMode's requests up to check 1: purges, latency 16, 9600 8N1, no flow control,
// RTS low, then the DTR low->high pulse.
void enter_bootloader(FalconFirmware& f) {
  ASSERT_TRUE(f.control(kSioReset, 1) && f.control(kSioReset, 2));
  ASSERT_TRUE(f.control(kSioLatency, 16) && f.control(kSioBaudRate, kDivisor9600));
  ASSERT_TRUE(f.control(kSioData, 8) && f.control(kSioFlowCtrl, 0));
  ASSERT_TRUE(f.control(kSioModemCtrl, 0x0200) && f.control(kSioModemCtrl, 0x0100));
  ASSERT_TRUE(f.control(kSioModemCtrl, 0x0101));
}

Bytes check1(FalconFirmware& f) {
  f.receive(Bytes{0x0A, 0x43, 0x0D}, 0);
  return f.take(64);
}

Bytes check2(FalconFirmware& f) {
  f.control(kSioModemCtrl, 0x0100);
  f.control(kSioBaudRate, kDivisorCheck2);
  f.receive(Bytes{0x41}, 0);
  return f.take(64);
}

Bytes image(std::size_t n) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(i * 7 + 3);
  return b;
}

// loadFirmware: the image in chunks, each echoed back byte for byte; then setNormalMode.
void load(FalconFirmware& f, const Bytes& img) {
  for (std::size_t at = 0; at < img.size(); at += 128) {
    const Bytes chunk(img.begin() + static_cast<std::ptrdiff_t>(at),
                      img.begin() + static_cast<std::ptrdiff_t>(std::min(at + 128, img.size())));
    f.receive(chunk, 0);
    ASSERT_EQ(f.take(256), chunk) << "at " << at;
  }
  f.control(kSioLatency, 1);
  f.control(kSioBaudRate, kDivisorFirmware);
  f.control(kSioReset, 1);
}

TEST(FalconModel, BootloaderAnswersBothChecksAndEchoesTheImage) {
  FalconFirmware f;
  enter_bootloader(f);
  EXPECT_EQ(check1(f), (Bytes{0x0A, 0x44, 0x2C, 0x0D}));
  EXPECT_EQ(check2(f), Bytes{0x41});
  load(f, image(8000));
  EXPECT_EQ(f.stage(), Stage::kRunning);
  EXPECT_EQ(f.image_size(), 8000u);
}

TEST(FalconModel, ChecksOnlyAtTheirRates) {
  FalconFirmware f;
  enter_bootloader(f);
  f.control(kSioBaudRate, kDivisorFirmware);
  EXPECT_TRUE(check1(f).empty()) << "check 1 answered at the wrong rate";
  f.control(kSioBaudRate, kDivisor9600);
  EXPECT_FALSE(check1(f).empty());
  f.control(kSioBaudRate, kDivisorCheck2);
  f.receive(Bytes{0x41}, 0);  // DTR still high
  EXPECT_TRUE(f.take(64).empty());
}

TEST(FalconModel, FailsTheFirstTryWhenAskedAndTakesTheSecond) {
  FirmwareOptions o;
  o.fail_first_try = true;
  FalconFirmware f(o);
  enter_bootloader(f);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(check1(f).empty());
  enter_bootloader(f);
  EXPECT_EQ(check1(f), (Bytes{0x0A, 0x44, 0x2C, 0x0D}));
}

TEST(FalconModel, RejectsAnImplausibleImage) {
  FalconFirmware f;
  enter_bootloader(f);
  check1(f);
  check2(f);
  load(f, image(1000));
  EXPECT_EQ(f.stage(), Stage::kRejected);
  f.receive(encode_packet({0, 0, 0}, 0), 0);
  EXPECT_EQ(f.pending(), 0u);
}

FalconFirmware running(const FirmwareOptions& o = {}) {
  FalconFirmware f(o);
  enter_bootloader(f);
  check1(f);
  check2(f);
  load(f, image(4096));
  return f;
}

TEST(FalconModel, PacketsNibblesAndMalformedCommands) {
  const auto p = encode_packet({0x1234, -2, 0}, 0x0E);
  const Bytes want{'<',  0x45, 0x44, 0x43, 0x42, 0x4F, 0x50, 0x50,
                   0x50, 0x41, 0x41, 0x41, 0x41, 0x4F, 0x41, '>'};
  EXPECT_EQ(Bytes(p.begin(), p.end()), want);
  Decoded d{};
  ASSERT_TRUE(decode_packet(p.data(), d));
  EXPECT_EQ(d.values[0], 0x1234);
  EXPECT_EQ(d.values[1], -2);

  FirmwareOptions o;
  o.buttons = 0x5;
  FalconFirmware f = running(o);
  ASSERT_EQ(f.stage(), Stage::kRunning);
  f.receive(encode_packet({0, 0, 0}, 0x0A), 0.0);  // green and red
  auto r = f.take(64);
  ASSERT_EQ(r.size(), kPacket);
  ASSERT_TRUE(decode_packet(r.data(), d));
  EXPECT_EQ(d.values, (std::array<std::int16_t, 3>{0, 0, 0})) << "relative from power-on";
  EXPECT_EQ(d.flags, 0x05);
  EXPECT_EQ(f.leds(), 0x0A);
  // Garbage, a '<' with a bad nibble, then a packet split across two writes.
  Bytes bad{'x', 'y', '<', 0x20};
  bad.resize(4 + 14, 0x41);
  f.receive(bad, 0.001);
  const auto good = encode_packet({10, 20, 30}, 0);
  f.receive(Bytes(good.begin(), good.begin() + 5), 0.001);
  f.receive(Bytes(good.begin() + 5, good.end()), 0.002);
  EXPECT_EQ(f.take(64).size(), kPacket);
  EXPECT_EQ(f.packets(), 2u);
  EXPECT_GE(f.malformed(), 2u);
}

TEST(FalconModel, SilentHungAndPurged) {
  FirmwareOptions o;
  o.silent_firmware = true;
  FalconFirmware s = running(o);
  s.receive(encode_packet({0, 0, 0}, 0), 0);
  EXPECT_EQ(s.pending(), 0u);
  EXPECT_EQ(s.packets(), 1u);
  FalconFirmware f = running();
  f.receive(encode_packet({0, 0, 0}, 0), 0);
  EXPECT_EQ(f.pending(), kPacket);
  const auto purges = f.purges();
  f.control(kSioReset, 1);
  EXPECT_EQ(f.pending(), 0u);
  EXPECT_EQ(f.purges(), purges + 1);
  f.hang();
  f.receive(encode_packet({0, 0, 0}, 0), 0.001);
  EXPECT_EQ(f.pending(), 0u);
}

TEST(FalconModel, JacobianMatchesForwardKinematicsDifferences) {
  for (const Vec3& x : {Vec3{0, 0, 0.11}, Vec3{0.02, -0.01, 0.13}, Vec3{-0.03, 0.02, 0.15}}) {
    const auto theta = inverse_kinematics(x);
    ASSERT_TRUE(theta);
    const auto back = forward_kinematics(*theta, Vec3{0, 0, 0.12});
    ASSERT_TRUE(back);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR((*back)[i], x[i], 1e-9);
    const auto j = jacobian(x);
    ASSERT_TRUE(j);
    const double h = 1e-6;
    for (int c = 0; c < 3; ++c) {
      Vec3 up = *theta, down = *theta;
      up[c] += h;
      down[c] -= h;
      const auto xu = forward_kinematics(up, x), xd = forward_kinematics(down, x);
      ASSERT_TRUE(xu && xd);
      for (int r = 0; r < 3; ++r) {
        const double fd = ((*xu)[r] - (*xd)[r]) / (2 * h);
        EXPECT_NEAR((*j)[r][c], fd, 1e-5 + 1e-4 * std::abs(fd)) << r << "," << c;
      }
    }
  }
  // Stamper's solution at the centre (libnifalcon's IK gives 16.19 degrees at z 0.11).
  EXPECT_NEAR(inverse_kinematics({0, 0, 0.11})->at(0) * 180 / M_PI, 16.188, 0.01);
}

TEST(FalconModel, MotorForceIsTheTorquesThroughTheJacobian) {
  FalconMechanism m;
  const std::array<std::int16_t, 3> counts{1000, -500, 250};
  m.set_motor_commands(counts);
  const Vec3 f = m.motor_force();
  // Virtual work: tau = J^T F must give back each arm's torque, -counts / 10000 N m.
  const auto j = jacobian(m.position());
  ASSERT_TRUE(j);
  for (int i = 0; i < 3; ++i) {
    const double tau = (*j)[0][i] * f[0] + (*j)[1][i] * f[1] + (*j)[2][i] * f[2];
    EXPECT_NEAR(tau, -counts[i] / 10000.0, 1e-9);
  }
  // Equal commands on all three arms push straight along z at the centre.
  m.set_motor_commands({2000, 2000, 2000});
  const Vec3 z = m.motor_force();
  EXPECT_NEAR(z[0], 0, 1e-9);
  EXPECT_NEAR(z[1], 0, 1e-9);
  EXPECT_GT(std::abs(z[2]), 1.0);
}

TEST(FalconModel, ForceMovesTheEncodersAndHomingMakesThemAbsolute) {
  FalconFirmware f = running();
  double t = 0;
  // Homing mode and a push outward (+z), as a user sweeps the grip out: the arms pass 35 deg.
  const auto push = [&](std::uint8_t flags, std::int16_t c) {
    for (int i = 0; i < 400; ++i, t += 0.001) {
      f.mechanism().set_hand_force({0, 0, 0});
      f.receive(encode_packet({c, c, c}, flags), t);
      f.take(64);
    }
  };
  const Vec3 before = f.mechanism().position();
  push(0x01, -3000);
  const Vec3 after = f.mechanism().position();
  EXPECT_GT(std::abs(after[2] - before[2]), 0.005) << "the commanded force moved nothing";
  EXPECT_EQ(f.homed(), 0x07) << "z " << after[2];
  const auto enc = f.encoders();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(enc[i], std::lround(counts_of_theta(f.mechanism().arm_angles()[i])), 1);
  }
}

}  // namespace
}  // namespace hapticd::reference::falcon
