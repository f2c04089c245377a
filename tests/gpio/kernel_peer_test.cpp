// The gpio-sim peer's writes, on a directory of its own: the simulated lines' `pull`
// attributes are FIFOs, so the test sees every edge the peer puts on the wires.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "gpio_example.h"
#include "sim/peers/gpio/gpio_peer.h"
#include "sim/peers/peer_runner.h"

namespace hapticd::drivers::gpio {
namespace {

namespace fs = std::filesystem;

struct FakeChip {
  FakeChip() {
    root = fs::temp_directory_path() / ("hapticd-gpiosim-" + std::to_string(getpid()));
    fs::remove_all(root);
    for (int i = 0; i < 5; ++i) {
      const fs::path d = root / ("sim_gpio" + std::to_string(i));
      fs::create_directories(d);
      std::ofstream(d / "value") << "0\n";
      mkfifo((d / "pull").c_str(), 0600);
      fifo[i] = ::open((d / "pull").c_str(), O_RDONLY | O_NONBLOCK);
    }
    std::ofstream(root / "channel0")
        << "period=50000 duty_cycle=0 polarity=normal enabled=0 applies=0\n";
  }
  ~FakeChip() {
    for (int f : fifo) ::close(f);
    fs::remove_all(root);
  }
  std::string drain(int line) {
    std::string out;
    char buf[4096];
    ssize_t n;
    while ((n = ::read(fifo[line], buf, sizeof buf)) > 0)
      out.append(buf, static_cast<std::size_t>(n));
    return out;
  }
  fs::path root;
  int fifo[5];
};

TEST(GpioKernelPeer, AtRestItPutsTheLevelsOnceAndNothingMore) {
  FakeChip chip;
  const config::Config cfg = load_gpio_example(
      {"loop.rate_hz=200", "device.gpio.counts_per_unit=20000", "device.sim.counts_per_unit=20000",
       "device.gpio.start_count=-400", "device.sim.operator.setpoint.start=4",
       "device.sim.initial_position=-0.020025", "device.sim.operator.setpoint.rest=-0.020025"});
  auto peer = wiring::find_driver("gpio").peer.make_peer_on(
      cfg, chip.root.string() + "," + (chip.root / "channel0").string());
  sim::PeerRunner runner(*peer);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  runner.stop();
  EXPECT_EQ(runner.error(), "");
  const std::string a = chip.drain(0), b = chip.drain(1), f = chip.drain(3);
  EXPECT_EQ(f, "pull-up") << "nFAULT released";
  // Count -401 (50 um counts, x = -0.02 m less a rounding hair): state (0, 1).
  EXPECT_EQ(a, "pull-down") << "A: '" << a << "' B: '" << b << "'";
  EXPECT_EQ(b, "pull-up") << "at rest: the levels once, no edge after";
}

}  // namespace
}  // namespace hapticd::drivers::gpio
