// Which way a positive level pushes through evdev, as <linux/input.h> (struct ff_effect)
// encodes the direction: "0 deg -> 0x0000 (down), 90 deg -> 0x4000 (left), 180 deg -> 0x8000
// (up), 270 deg -> 0xC000 (right)". The shipped configuration and the driver's default ask for
// 0xC000, so a positive hapticd force pushes toward +x; the simulated device (sim/peers/evdev)
// renders the effect that way. A simulated device with the old sign (+sin) fails here, in
// every run, not only in the kernel test machine.
#include <gtest/gtest.h>
#include <sys/socket.h>

#include <array>
#include <fstream>
#include <sstream>

#include "config/config_loader.h"
#include "drivers/evdev/evdev_settings.h"
#include "drivers/evdev/evdev_wire.h"
#include "sim/peers/evdev/evdev_peer.h"
#include "wiring/registry.h"

namespace hapticd::drivers::evdev {
namespace {

config::Config shipped() {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/evdev.yaml");
  std::stringstream s;
  s << in.rdbuf();
  return config::load_config_text(s.str(), "evdev.yaml", {}, ".", wiring::driver_schemas());
}

TEST(EvdevDirection, TheShippedConfigurationAndTheDefaultAskForRight) {
  EXPECT_EQ(direction_of(evdev_settings(shipped()).direction_deg), 0xC000);
  EXPECT_EQ(direction_of(EvdevSettings{}.direction_deg), 0xC000) << "the default";
  EXPECT_EQ(wire::Effect{}.direction, 0xC000);
}

// The simulated device on its socketpair, driven message by message as the driver would.
struct Peer {
  Peer() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0);
    host = io::UniqueFd(fds[0]);
    peer = std::make_unique<sim::evdev::SocketEvdevPeer>(cfg, io::UniqueFd(fds[1]), 0);
  }
  void send(std::size_t n) {
    ASSERT_EQ(::send(host.get(), buf.data(), n, 0), static_cast<ssize_t>(n));
    peer->service();
  }
  // The force the device applies for `level` at `direction`, the effect uploaded and played.
  double force(std::uint16_t direction, std::int16_t level) {
    send(wire::encode_upload({-1, direction, 0, 0}, buf));
    send(wire::encode_write_ff(0, 1, buf));  // play effect 0
    send(wire::encode_upload({0, direction, level, 0}, buf));
    const double f = peer->applied_force();
    send(wire::encode_write_ff(0, 0, buf));
    wire::Message erase;  // EVIOCRMFF of effect 0: the device holds one
    erase.type = wire::Type::kErase;
    std::vector<std::uint8_t> bytes;
    wire::encode(erase, bytes);
    EXPECT_EQ(::send(host.get(), bytes.data(), bytes.size(), 0),
              static_cast<ssize_t>(bytes.size()));
    peer->service();
    return f;
  }
  config::Config cfg = shipped();
  io::UniqueFd host;
  std::unique_ptr<sim::evdev::SocketEvdevPeer> peer;
  std::array<std::uint8_t, 64> buf{};
};

TEST(EvdevDirection, TheSimulatedDevicePushesAsTheKernelEncodesTheDirection) {
  Peer p;
  const double half = 0.5 * evdev_settings(p.cfg).force_full_scale;
  EXPECT_NEAR(p.force(0xC000, 0x4000), half, 1e-3) << "270 degrees, right: toward +x";
  EXPECT_NEAR(p.force(0x4000, 0x4000), -half, 1e-3) << "90 degrees, left: toward -x";
  EXPECT_NEAR(p.force(0x4000, -0x4000), half, 1e-3) << "left with a negative level: +x";
  EXPECT_NEAR(p.force(0x0000, 0x4000), 0.0, 1e-9) << "down: nothing along x";
}

}  // namespace
}  // namespace hapticd::drivers::evdev
