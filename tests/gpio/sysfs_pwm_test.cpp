// The sysfs PWM writer on a directory of its own (the sysfs root is configurable): duty_cycle
// and enable are FIFOs, so the test sees every write(2) the writer makes, in order. (Reading
// one finds what a test wrote into it, or nothing: a channel that is not enabled.)
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "drivers/device.h"
#include "drivers/gpio/sysfs_pwm.h"

namespace hapticd::drivers::gpio {
namespace {

namespace fs = std::filesystem;

class FakePwmRoot : public testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("hapticd-pwm-" + std::to_string(getpid()));
    fs::remove_all(root_);
    dir_ = root_ / "pwmchip3" / "pwm1";
    fs::create_directories(dir_);
    for (const char* f : {"export", "unexport"}) std::ofstream(root_ / "pwmchip3" / f);
    for (const char* f : {"period", "polarity"})
      std::ofstream(dir_ / f) << (f[1] == 'o' ? "normal\n" : "0\n");
    for (const char* f : {"duty_cycle", "enable"}) {
      ASSERT_EQ(mkfifo((dir_ / f).c_str(), 0600), 0);
      // Our read end first, so the writer's open does not block.
      fds_[f[0] == 'd' ? 0 : 1] = ::open((dir_ / f).c_str(), O_RDONLY | O_NONBLOCK);
    }
  }
  void TearDown() override {
    for (int fd : fds_) ::close(fd);
    fs::remove_all(root_);
  }
  std::string drain(int which) {
    std::string out;
    char buf[256];
    ssize_t n;
    while ((n = ::read(fds_[which], buf, sizeof buf)) > 0)
      out.append(buf, static_cast<std::size_t>(n));
    return out;
  }
  std::string slurp(const char* f) {
    std::ifstream in(dir_ / f);
    std::string s;
    std::getline(in, s);
    return s;
  }
  PwmChannel channel(bool inversed = false) {
    PwmChannel c;
    c.sysfs_root = root_.string();
    c.chip = 3;
    c.channel = 1;
    c.period_ns = 40'000;
    c.inversed = inversed;
    return c;
  }

  fs::path root_, dir_;
  int fds_[2] = {-1, -1};
};

// Issue 22: every stop is duty 0 on the enabled channel (a disabled channel's output is
// undefined, Documentation/driver-api/pwm.rst): open ends with the channel enabled at duty 0,
// and nothing after it writes `enable` again.
TEST_F(FakePwmRoot, OpenEnablesTheChannelAtZeroDutyAndOnlyTheDutyChangesAfter) {
  SysfsPwm pwm;
  pwm.open(channel(true));
  EXPECT_EQ(drain(0), "0\n") << "duty to zero";
  EXPECT_EQ(drain(1), "1\n") << "enabled once, after the period and the polarity";
  EXPECT_EQ(slurp("period"), "40000");
  EXPECT_EQ(slurp("polarity"), "inversed");
  EXPECT_EQ(pwm.path(), (dir_).string());

  EXPECT_EQ(pwm.write(0), 0);
  EXPECT_EQ(drain(0), "") << "duty unchanged: no write";
  EXPECT_EQ(pwm.write(12'000), 0);
  EXPECT_EQ(pwm.write(12'000), 0);
  EXPECT_EQ(pwm.write(12'000), 0);
  EXPECT_EQ(drain(0), "12000\n") << "one write for three ticks at the same duty";
  EXPECT_EQ(pwm.write(0), 0);
  EXPECT_EQ(drain(0), "0\n") << "the stop";
  pwm.close();
  EXPECT_EQ(drain(1), "") << "never disabled: not by a stop, not by close";
  EXPECT_EQ(pwm.writes(), 2u);
}

// A channel some earlier run or tool left driving is stopped before anything else is changed.
TEST_F(FakePwmRoot, AChannelLeftDrivingIsStoppedFirst) {
  const int writer = ::open((dir_ / "duty_cycle").c_str(), O_WRONLY | O_NONBLOCK);
  ASSERT_GE(writer, 0);
  ASSERT_EQ(::write(writer, "30000\n", 6), 6);  // what open() reads as the current duty
  ::close(writer);
  SysfsPwm pwm;
  pwm.open(channel());
  EXPECT_EQ(drain(0), "0\n0\n") << "zero at once, and again once the period is set";
  EXPECT_EQ(drain(1), "1\n");
}

TEST_F(FakePwmRoot, EmergencyStopWritesZeroOnTheOpenDescriptor) {
  SysfsPwm pwm;
  pwm.open(channel());
  drain(0);
  drain(1);
  pwm.write(30'000);
  EXPECT_EQ(drain(0), "30000\n");
  pwm.emergency_stop();
  EXPECT_EQ(drain(0), "0\n");
  EXPECT_EQ(drain(1), "") << "the channel stays enabled";
}

// The instance's udev rule exports the channel as root and leaves the chip's export root's.
TEST_F(FakePwmRoot, AnExportedChannelIsUsedWithoutTheChipsExport) {
  fs::remove(root_ / "pwmchip3" / "export");
  SysfsPwm pwm;
  ASSERT_NO_THROW(pwm.open(channel()));
  EXPECT_TRUE(pwm.is_open());
  EXPECT_EQ(slurp("period"), "40000");
}

TEST_F(FakePwmRoot, MissingChipOrUnwritableChannelIsADeviceErrorNamingIt) {
  SysfsPwm pwm;
  PwmChannel c = channel();
  c.chip = 9;
  try {
    pwm.open(c);
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("pwmchip9"), std::string::npos) << e.what();
  }
  c = channel();
  c.channel = 5;  // not exported, and the export file is a plain file: nothing appears
  try {
    pwm.open(c);
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("pwm5/duty_cycle"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(pwm.is_open());
  EXPECT_EQ(pwm.write(1), EBADF);
}

}  // namespace
}  // namespace hapticd::drivers::gpio
