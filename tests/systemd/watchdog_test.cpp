// The watchdog on a device that can tell: a GPIO instance (a sysfs PWM keeps its last duty when
// nobody writes it, and the PWM simulator shows what the PWM core applied) whose loop thread
// is stopped in the middle of a push, alone: its supervisor runs on. systemd must act within
// WatchdogSec, and what its WatchdogSignal makes hapticd do must leave the motor at duty 0
// while the loop thread is still stuck; TimeoutStopSec later systemd kills what is left.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/ptrace.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>
#include <thread>

#include "sysfs.h"
#include "transport_rig.h"

namespace hapticd::systemd_test {
namespace {

// One thread of another process held stopped, as a thread blocked in a driver or starved of
// the CPU would be. A signal cannot stop a single thread (SIGSTOP stops them all, and systemd
// sends SIGCONT with its watchdog signal); a ptrace interrupt can.
class FrozenThread {
 public:
  explicit FrozenThread(pid_t tid) : tid_(tid) {
    if (ptrace(PTRACE_SEIZE, tid_, nullptr, nullptr) != 0) return;
    int status = 0;
    frozen_ = ptrace(PTRACE_INTERRUPT, tid_, nullptr, nullptr) == 0 &&
              waitpid(tid_, &status, __WALL) == tid_ && WIFSTOPPED(status);
  }
  // The thread's end, when its process is killed: reaped here (as its tracer must), or the
  // process would never be seen to exit. True once it has.
  bool wait_end(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      const pid_t r = waitpid(tid_, &status, __WALL | WNOHANG);
      if (r == -1 || (r == tid_ && (WIFEXITED(status) || WIFSIGNALED(status)))) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }
  ~FrozenThread() {
    if (frozen_ && ptrace(PTRACE_DETACH, tid_, nullptr, nullptr) != 0)
      wait_end(std::chrono::seconds(10));
  }
  bool frozen() const { return frozen_; }

 private:
  pid_t tid_;
  bool frozen_ = false;
};

class Watchdog : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(install_once(), "") << "installing as a user does"; }
};

TEST_F(Watchdog, AStuckLoopThreadIsCaughtWithinWatchdogSecAndItsSignalLeavesDutyZero) {
  GpioMachine m;
  m.chip.set_pull(3, true);  // nFAULT released
  Instance stuck("stuck", m.yaml());
  InstanceRules rules(stuck, m.trigger());
  ASSERT_EQ(rules.error(), "");
  DropIn pwm_writable(stuck, m.drop_in());
  // The plant runs first, as a real one does: the direction check, before READY=1, pushes it.
  SimulatedDevice device(load_config(m.yaml(), stuck.config_path()), m.endpoint());
  ASSERT_EQ(stuck.systemctl("start").status, 0) << stuck.journal();
  // Into the wall, until it pushes.
  EXPECT_GE(wait_for_contact(stuck, 25, std::chrono::seconds(60)), 25) << stuck.journal();
  kernel_test::wait_until([&] { return m.pwm.applied(0).duty_cycle_ns > 0; },
                          std::chrono::seconds(20), "a duty on the PWM");

  const pid_t pid = stuck.main_pid();
  pid_t rt = 0;
  for (const ThreadInfo& t : threads_of(pid)) rt = t.comm == "hapticd-rt" ? t.tid : rt;
  ASSERT_GT(rt, 0) << "the loop thread";
  FrozenThread frozen(rt);
  ASSERT_TRUE(frozen.frozen()) << "ptrace: " << std::strerror(errno);
  const unsigned long long stopped_at = monotonic_us();
  const std::uint64_t duty = m.pwm.applied(0).duty_cycle_ns;
  ASSERT_GT(duty, 0u) << "the motor driven when the loop stopped";

  // systemd: within WatchdogSec of the last tick, its signal.
  const std::string caught = stuck.wait_journal("Watchdog timeout");
  const unsigned long long at = stuck.journal_monotonic_us("Watchdog timeout");
  ASSERT_GT(at, 0u) << caught;
  const double after_s = static_cast<double>(at - stopped_at) / 1e6;
  RecordProperty("watchdog_after_s", std::to_string(after_s));
  EXPECT_GE(after_s, 1.5) << "WatchdogSec=2s, counted from the last ping";
  EXPECT_LE(after_s, 3.5) << "WatchdogSec=2s, and the emulator's slack";
  // hapticd: a stop its loop cannot take; the emergency stop, from the supervisor.
  kernel_test::wait_until([&] { return m.pwm.applied(0).duty_cycle_ns == 0; },
                          std::chrono::seconds(3), "duty 0 after the watchdog's signal");
  EXPECT_EQ(kill(pid, 0), 0) << "zeroed by hapticd while it still ran, not by its end";
  EXPECT_TRUE(m.pwm.applied(0).enabled) << "duty 0 on the enabled channel";
  const std::string j = stuck.wait_journal("emergency stop");
  EXPECT_TRUE(contains(j, "SIGABRT received: stopping")) << j;
  EXPECT_TRUE(contains(stuck.journal("err"), "wrote the device's emergency stop")) << j;

  // TimeoutStopSec (5 s) after its signal, systemd kills the process the thread is stuck in.
  EXPECT_TRUE(frozen.wait_end(std::chrono::seconds(20))) << stuck.journal();
  EXPECT_EQ(stuck.wait_inactive(), "failed");
  EXPECT_EQ(stuck.property("Result"), "watchdog");
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 0u) << "and so it stays";
  std::cout << stuck.journal() << "\n";
}

}  // namespace
}  // namespace hapticd::systemd_test
