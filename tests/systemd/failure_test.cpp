// What an operator sees when an instance cannot or may not run: a configuration the gate
// refuses fails the start with exit 3 and the reason in `systemctl status`; a configuration
// error with exit 2 and FILE:LINE in the journal, as an error; and a process that stops
// ticking (stopped whole with SIGSTOP) is caught by systemd's watchdog, whose signal then
// stops hapticd cleanly.
#include <gtest/gtest.h>
#include <signal.h>

#include <thread>

#include "systemd_rig.h"

namespace hapticd::systemd_test {
namespace {

class Failure : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(install_once(), "") << "installing as a user does"; }
};

TEST_F(Failure, AWallTheGateRefusesFailsTheStartWithExit3AndTheReasonInSystemctlStatus) {
  // 1000 N/m at 100 Hz needs b_req 5.2 N s/m of the device's 2.
  Instance refused("refused", config_text("sim.yaml", guest_sets({"wall.stiffness=1000"})));
  const Shell start = refused.systemctl("start");
  EXPECT_NE(start.status, 0) << "systemctl start fails";
  EXPECT_EQ(refused.property("ActiveState"), "failed");
  EXPECT_EQ(refused.property("ExecMainStatus"), "3");
  refused.wait_journal("Failed with result");
  const Shell status = refused.systemctl("status");
  EXPECT_TRUE(contains(status.out, "status=3")) << status.out;
  EXPECT_TRUE(contains(status.out, "fail: passivity: required damping b_req = 5.2 N s/m exceeds"))
      << "the reason, in the lines status shows:\n"
      << status.out;
  const std::string errors = refused.journal("err");
  EXPECT_TRUE(contains(errors, "[error] gate: passivity: required damping b_req = 5.2")) << errors;
  EXPECT_FALSE(contains(refused.journal(), "output enabled")) << "never enabled";
}

TEST_F(Failure, AConfigurationErrorFailsWithExit2AndFileAndLineInTheJournal) {
  Instance broken("broken", "wall:\n  stiffness: -5\n  dampnig: 0.2\n");
  EXPECT_NE(broken.systemctl("start").status, 0);
  EXPECT_EQ(broken.property("ExecMainStatus"), "2");
  broken.wait_journal("Failed with result");
  const std::string errors = broken.journal("err");
  EXPECT_TRUE(contains(errors,
                       "hapticd: /etc/hapticd/broken.yaml:2: wall.stiffness: must be >= 0, "
                       "got '-5'"))
      << errors;
  EXPECT_TRUE(contains(errors,
                       "/etc/hapticd/broken.yaml:3: wall.dampnig: unknown key (did you "
                       "mean 'damping'?)"))
      << errors;
  const Shell status = broken.systemctl("status");
  EXPECT_TRUE(contains(status.out, "status=2/INVALIDARGUMENT")) << status.out;
}

// SIGSTOP stops every thread: nothing ticks and nothing pings. systemd's watchdog signal
// (SIGABRT) comes with a SIGCONT, so hapticd wakes to a stop and ends as for SIGTERM.
TEST_F(Failure, AStoppedProcessIsCaughtByTheWatchdogAndStopsCleanlyOnItsSignal) {
  Instance frozen("frozen", config_text("sim.yaml", guest_sets({"wall.stiffness=250"})));
  ASSERT_EQ(frozen.systemctl("start").status, 0) << frozen.journal();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const pid_t pid = frozen.main_pid();
  ASSERT_GT(pid, 0);
  const unsigned long long stopped_at = monotonic_us();
  ASSERT_EQ(kill(pid, SIGSTOP), 0);
  EXPECT_EQ(frozen.wait_inactive(), "failed");
  EXPECT_EQ(frozen.property("Result"), "watchdog");
  const std::string j = frozen.wait_journal("Failed with result");
  const unsigned long long caught = frozen.journal_monotonic_us("Watchdog timeout");
  ASSERT_GT(caught, 0u) << j;
  const double after_s = static_cast<double>(caught - stopped_at) / 1e6;
  RecordProperty("watchdog_after_s", std::to_string(after_s));
  EXPECT_GE(after_s, 1.5) << "WatchdogSec=2s, counted from the last ping";
  EXPECT_LE(after_s, 3.5) << "WatchdogSec=2s, and the emulator's slack";
  EXPECT_TRUE(
      contains(j, "Killing process " + std::to_string(pid) + " (hapticd) with signal SIGABRT"))
      << j;
  EXPECT_TRUE(contains(j, "SIGABRT received: stopping")) << j;
  EXPECT_TRUE(contains(j, "output         sim configured, disabled, last command 0 N")) << j;
  EXPECT_EQ(frozen.property("ExecMainStatus"), "0") << "it stopped, it was not killed";
}

}  // namespace
}  // namespace hapticd::systemd_test
