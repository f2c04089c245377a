// The rules `hapticd udev-rules` writes, applied by the real udevd (Debian's systemd-udevd) in
// the kernel test machine to real devices: the configured gpio-sim chip is the group's and
// the other chip is not; the configured channel of the PWM simulator is exported by udev and
// only its four attributes are the group's; the configured CAN controller (slcan) is set to
// the configured bitrate and brought up, and another controller is left as it was. udevd is
// stopped afterwards: the other kernel tests of the same boot run without it.
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "gpio_sim_chip.h"
#include "process.h"
#include "pwm_sim.h"
#include "service/commands/udev_rules.h"
#include "service/config_source.h"
#include "slcan_tty.h"

namespace hapticd::service {
namespace {

using hapticd::testing::has;

using hapticd::testing::ProcessResult;
using hapticd::testing::run_process;

// The guest runs its tests in a chroot, where udevadm would otherwise ignore every request.
ProcessResult sh(const std::string& command) {
  return run_process({"/bin/sh", "-c", command}, {"SYSTEMD_IGNORE_CHROOT=1"});
}

struct stat stat_of(const std::string& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return st;
}

std::string rules_for(const std::string& example, const std::vector<std::string>& sets) {
  return instance_udev_rules(
      load_config({std::string(HAPTICD_SOURCE_DIR) + "/config/" + example, sets}), "kt");
}

// udevd for the test's length, with `rules` installed where an administrator puts them. A
// host may still carry the device rules an older hapticd installed for every interface and
// chip (a `cmake --install` before they went wrote them to /usr/local/lib/udev/rules.d,
// whatever its prefix): they are masked here as an administrator masks a rule, with a
// same-named link to /dev/null in /etc/udev/rules.d, so only the instance's rules act.
class Udevd {
 public:
  explicit Udevd(const std::string& rules) {
    namespace fs = std::filesystem;
    fs::create_directories("/etc/udev/rules.d");
    std::ofstream(kRules) << rules;
    for (const char* dir : {"/usr/local/lib/udev/rules.d", "/usr/lib/udev/rules.d"}) {
      std::error_code ec;
      for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
        const std::string name = e.path().filename();
        if (name.find("hapticd") == std::string::npos || name == "60-hapticd-rt.rules") continue;
        masked_.push_back("/etc/udev/rules.d/" + name);
        fs::create_symlink("/dev/null", masked_.back(), ec);
      }
    }
    started_ = sh("/lib/systemd/systemd-udevd --daemon 2>&1");
  }
  ~Udevd() {
    sh("udevadm control --exit");
    std::filesystem::remove(kRules);
    for (const std::string& m : masked_) std::filesystem::remove(m);
  }
  const ProcessResult& started() const { return started_; }
  // What `udevadm trigger --action=add` replays for the devices that were there before.
  static ProcessResult trigger(const std::string& matches) {
    return sh("udevadm trigger --action=add " + matches +
              " 2>&1 && udevadm settle --timeout=120 2>&1");
  }

 private:
  static constexpr const char* kRules = "/etc/udev/rules.d/70-hapticd-kt.rules";
  ProcessResult started_;
  std::vector<std::string> masked_;
};

TEST(UdevRulesOnKernel, AnInstancesRulesGiveItsChipItsChannelAndItsBusAndNothingElse) {
  ASSERT_EQ(sh("getent group hapticd >/dev/null || groupadd -r hapticd").exit_code, 0);
  const group* g = ::getgrnam("hapticd");
  ASSERT_NE(g, nullptr);
  const gid_t hapticd = g->gr_gid;

  kernel_test::GpioSimChip ours(5, "kt-ours", {}, "kt-ours");
  kernel_test::GpioSimChip other(2, "kt-other", {}, "kt-other");
  kernel_test::PwmSim pwm;
  const std::string pwmchip = pwm.chip_path().substr(pwm.chip_path().rfind('/') + 1);
  Slcan bus, other_bus;
  ASSERT_FALSE(bus.name().empty() || other_bus.name().empty()) << "slcan";

  const std::string rules = rules_for("gpio.yaml", {"device.gpio.chip=" + ours.chip_name(),
                                                    "device.gpio.pwm.chip=" + pwmchip.substr(7),
                                                    "device.gpio.pwm.channel=1"}) +
                            rules_for("can-cia402.yaml", {"device.can.interface=" + bus.name(),
                                                          "device.can.bitrate=500000"});
  Udevd udevd(rules);
  ASSERT_EQ(udevd.started().exit_code, 0) << udevd.started().out;
  const ProcessResult t = Udevd::trigger(
      "--subsystem-match=gpio --subsystem-match=pwm --sysname-match=" + ours.chip_name() +
      " --sysname-match=" + other.chip_name() + " --sysname-match=" + pwmchip);
  ASSERT_EQ(t.exit_code, 0) << t.out;
  const ProcessResult n = Udevd::trigger("--subsystem-match=net --sysname-match=" + bus.name() +
                                         " --sysname-match=" + other_bus.name());
  ASSERT_EQ(n.exit_code, 0) << n.out;

  // GPIO: the configured chip is the group's, the other one root's alone.
  const struct stat mine = stat_of(ours.dev_path());
  EXPECT_EQ(mine.st_gid, hapticd);
  EXPECT_EQ(mine.st_mode & 0777, 0660u);
  EXPECT_EQ(stat_of(other.dev_path()).st_gid, 0u) << "a chip no configuration names";

  // PWM: channel 1 exported by udev, its four attributes group-writable; the chip's export,
  // unexport and channel 0 stay root's.
  const std::string chip = pwm.chip_path();
  for (const char* f : {"period", "duty_cycle", "polarity", "enable"}) {
    const struct stat st = stat_of(chip + "/pwm1/" + f);
    EXPECT_EQ(st.st_gid, hapticd) << f;
    EXPECT_NE(st.st_mode & S_IWGRP, 0u) << f;
  }
  EXPECT_EQ(stat_of(chip + "/export").st_gid, 0u);
  EXPECT_EQ(stat_of(chip + "/unexport").st_gid, 0u);
  EXPECT_FALSE(std::filesystem::exists(chip + "/pwm0")) << "a channel no configuration names";

  // CAN: the configured controller at the configured bitrate and up; the other one untouched.
  const ProcessResult link = sh("ip -details link show " + bus.name());
  EXPECT_TRUE(has(link.out, "bitrate 500000")) << link.out;
  // (restart-ms is asked for too, udev_rules_test.cpp; slcan, which cannot go bus-off,
  // keeps 0.)
  EXPECT_TRUE(has(link.out, ",UP")) << link.out;
  const ProcessResult untouched = sh("ip -details link show " + other_bus.name());
  EXPECT_FALSE(has(untouched.out, ",UP")) << untouched.out;
  EXPECT_FALSE(has(untouched.out, "bitrate 500000")) << untouched.out;
  sh("echo 1 >" + chip + "/unexport");
}

}  // namespace
}  // namespace hapticd::service
