// The sysfs PWM writer on a directory of its own (the sysfs root is configurable): duty_cycle
// and enable are FIFOs, so the test sees every write(2) the writer makes, in order.
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

TEST_F(FakePwmRoot, OpenSetsUpInOrderThenWritesOnlyWhatChanges) {
  SysfsPwm pwm;
  pwm.open(channel(true), false);
  EXPECT_EQ(drain(0), "0\n") << "duty to zero";
  EXPECT_EQ(drain(1), "") << "not enabled: left alone while the period and polarity change";
  EXPECT_EQ(slurp("period"), "40000");
  EXPECT_EQ(slurp("polarity"), "inversed");
  EXPECT_EQ(pwm.path(), (dir_).string());

  EXPECT_EQ(pwm.write(0, true), 0);
  EXPECT_EQ(drain(0), "") << "duty unchanged: no write";
  EXPECT_EQ(drain(1), "1\n");
  EXPECT_EQ(pwm.write(12'000, true), 0);
  EXPECT_EQ(pwm.write(12'000, true), 0);
  EXPECT_EQ(pwm.write(12'000, true), 0);
  EXPECT_EQ(drain(0), "12000\n") << "one write for three ticks at the same duty";
  EXPECT_EQ(pwm.write(0, false), 0);
  EXPECT_EQ(drain(0), "0\n");
  EXPECT_EQ(drain(1), "0\n");
  EXPECT_EQ(pwm.writes(), 4u);
}

TEST_F(FakePwmRoot, EmergencyStopWritesZeroOnTheOpenDescriptor) {
  SysfsPwm pwm;
  pwm.open(channel(), true);
  drain(0);
  pwm.write(30'000, true);
  EXPECT_EQ(drain(0), "30000\n");
  pwm.emergency_stop();
  EXPECT_EQ(drain(0), "0\n");
}

// The instance's udev rule exports the channel as root and leaves the chip's export root's.
TEST_F(FakePwmRoot, AnExportedChannelIsUsedWithoutTheChipsExport) {
  fs::remove(root_ / "pwmchip3" / "export");
  SysfsPwm pwm;
  ASSERT_NO_THROW(pwm.open(channel(), false));
  EXPECT_TRUE(pwm.is_open());
  EXPECT_EQ(slurp("period"), "40000");
}

TEST_F(FakePwmRoot, MissingChipOrUnwritableChannelIsADeviceErrorNamingIt) {
  SysfsPwm pwm;
  PwmChannel c = channel();
  c.chip = 9;
  try {
    pwm.open(c, false);
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("pwmchip9"), std::string::npos) << e.what();
  }
  c = channel();
  c.channel = 5;  // not exported, and the export file is a plain file: nothing appears
  try {
    pwm.open(c, false);
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("pwm5/duty_cycle"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(pwm.is_open());
  EXPECT_EQ(pwm.write(1, true), EBADF);
}

}  // namespace
}  // namespace hapticd::drivers::gpio
