// A crash while output is enabled: the guarded device's emergency_stop() runs before the
// signal ends the process, and the process still dies of that signal.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>

#include "service/run/crash_guard.h"

namespace hapticd::service {
namespace {

// Its emergency stop writes one byte to a pipe, as a driver writes a zero-force frame.
class PipeDevice final : public Device {
 public:
  explicit PipeDevice(int fd) : fd_(fd) {}
  std::string_view driver_name() const noexcept override { return "pipe"; }
  void emergency_stop() noexcept override {
    const char zero = '0';
    [[maybe_unused]] const ssize_t n = ::write(fd_, &zero, 1);
  }

 protected:
  DeviceInfo on_configure() override { return {"pipe", 0, 0}; }
  void on_enable() override {}
  void on_disable() noexcept override {}
  void on_close() noexcept override {}
  IoStatus on_read(std::span<PositionSample>) noexcept override { return IoStatus::kOk; }
  IoStatus on_write(std::span<const double>) noexcept override { return IoStatus::kOk; }
  std::string describe(const DeviceFault&) const override { return "pipe"; }

 private:
  int fd_;
};

int crash_child(int sig, int fd, bool guarded) {
  const pid_t pid = fork();
  if (pid == 0) {
    PipeDevice device(fd);
    if (guarded) guard_device_on_crash(&device);
    if (sig == SIGABRT) std::abort();
    raise(sig);
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status) ? WTERMSIG(status) : -1;
}

TEST(CrashGuard, AnyCrashWritesTheEmergencyStopThenDiesOfItsSignal) {
  for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) {
    SCOPED_TRACE(sig);
    int p[2];
    ASSERT_EQ(pipe(p), 0);
    EXPECT_EQ(crash_child(sig, p[1], true), sig);
    close(p[1]);
    char got = 0;
    EXPECT_EQ(read(p[0], &got, 1), 1);
    EXPECT_EQ(got, '0');
    close(p[0]);
  }
}

TEST(CrashGuard, NothingIsWrittenForADeviceNoLongerGuarded) {
  int p[2];
  ASSERT_EQ(pipe(p), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    PipeDevice device(p[1]);
    guard_device_on_crash(&device);
    guard_device_on_crash(nullptr);  // closed: nothing left to stop
    raise(SIGSEGV);
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  close(p[1]);
  char got = 0;
  EXPECT_EQ(read(p[0], &got, 1), 0);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGSEGV);
  close(p[0]);
}

}  // namespace
}  // namespace hapticd::service
