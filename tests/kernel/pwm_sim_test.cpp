// Sysfs PWM in the kernel test machine: a channel of hapticd's PWM simulator exported,
// configured and enabled through /sys/class/pwm, and the simulator reporting exactly what
// the PWM core applied, as the GPIO driver's PWM output and its peer will use them.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

#include "pwm_sim.h"
#include "sysfs.h"

namespace hapticd::kernel_test {
namespace {

using std::chrono::milliseconds;

// Exports a channel for one test and unexports it afterwards, as a driver would.
class ExportedChannel {
 public:
  ExportedChannel(const PwmSim& sim, unsigned channel)
      : sim_(sim), channel_(channel), dir_(sim.chip_path() + "/pwm" + std::to_string(channel)) {
    write_text(sim_.chip_path() + "/export", std::to_string(channel_));
    wait_until([&] { return path_exists(dir_ + "/enable"); }, milliseconds(5000),
               dir_ + " after export");
  }
  ~ExportedChannel() {
    try {
      write_text(sim_.chip_path() + "/unexport", std::to_string(channel_));
    } catch (const KernelFacilityError&) {
      // The next export of this channel would fail with EBUSY and say so.
    }
  }
  void set(const std::string& attr, const std::string& value) const {
    write_text(dir_ + "/" + attr, value);
  }

 private:
  const PwmSim& sim_;
  unsigned channel_;
  std::string dir_;
};

TEST(PwmSim, SysfsChannelConfiguredAndEnabledIsWhatTheSimulatorApplied) {
  PwmSim sim;
  ASSERT_GE(sim.npwm(), 2u);
  ExportedChannel pwm(sim, 1);
  const std::uint64_t start = sim.applied(1).applies;
  const std::uint64_t other_start = sim.applied(0).applies;

  pwm.set("period", "1000000");  // 1 kHz
  pwm.set("duty_cycle", "250000");
  pwm.set("polarity", "normal");
  pwm.set("enable", "1");
  const PwmApplied on = sim.applied(1);
  EXPECT_EQ(on.period_ns, 1000000u);
  EXPECT_EQ(on.duty_cycle_ns, 250000u);
  EXPECT_FALSE(on.inversed);
  EXPECT_TRUE(on.enabled);
  EXPECT_EQ(on.applies, start + 3);  // period, duty, enable; "normal" changed nothing
  EXPECT_EQ(sim.applied(0).applies, other_start) << "channel 0 was not touched";

  pwm.set("enable", "0");
  EXPECT_FALSE(sim.applied(1).enabled);
}

TEST(PwmSim, PeerWakesOnEachDutyWrite) {
  PwmSim sim;
  ExportedChannel pwm(sim, 0);
  pwm.set("period", "50000");
  pwm.set("enable", "1");
  for (const std::uint64_t duty : {10000u, 37500u, 0u}) {
    const std::uint64_t seen = sim.applied(0).applies;
    // The write comes from another thread once the peer is already waiting in poll().
    std::thread driver([&] {
      std::this_thread::sleep_for(milliseconds(50));
      pwm.set("duty_cycle", std::to_string(duty));
    });
    const auto applied = sim.wait_applied(0, seen, milliseconds(5000));
    driver.join();
    ASSERT_TRUE(applied.has_value()) << "no apply notified for duty " << duty;
    EXPECT_EQ(applied->duty_cycle_ns, duty);
    EXPECT_EQ(applied->period_ns, 50000u);
    EXPECT_EQ(applied->applies, seen + 1);
  }
  // A duty above the period is refused by the PWM core and never reaches the chip.
  const std::uint64_t before = sim.applied(0).applies;
  EXPECT_THROW(pwm.set("duty_cycle", "60000"), KernelFacilityError);
  EXPECT_EQ(sim.applied(0).applies, before);
  pwm.set("enable", "0");
}

}  // namespace
}  // namespace hapticd::kernel_test
