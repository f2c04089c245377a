// hapticd@demo, the simulated device, under the real systemd of the kernel test machine, as
// installed by `cmake --install`: started only once it servoes, in real time as user hapticd;
// its control socket for root and group hapticd alone; reload through the gate; a clean stop
// with the summary in the journal and the tick log in its state directory; its events'
// priorities; and the exposure systemd-analyze gives the running unit.
#include <gtest/gtest.h>
#include <pwd.h>
#include <sched.h>

#include <nlohmann/json.hpp>
#include <regex>
#include <thread>

#include "systemd_rig.h"

namespace hapticd::systemd_test {
namespace {

using nlohmann::json;

// config/sim.yaml at the machine's rate; the RT priority is not the default (80), so the test
// sees the configured one; max_force 2 N gives the gate a warning for the journal.
std::string demo_yaml(const std::string& stiffness = "250") {
  return config_text("sim.yaml", guest_sets({"loop.rt_priority=70", "wall.stiffness=" + stiffness,
                                             "device.max_force=2"}));
}

// `hapticctl -i NAME --json status` (as `user` unless empty): the answer, or null.
json ctl_status(const std::string& name, const std::string& user, Shell* raw = nullptr) {
  const std::string cmd = "hapticctl -i " + name + " --json status";
  const Shell r = user.empty() ? sh(cmd) : sh_as(user, cmd);
  if (raw != nullptr) *raw = r;
  const json j = json::parse(r.out, nullptr, false);
  return r.status == 0 && j.is_object() ? j : json();
}

// hapticd@demo started once for the checks that only look at it; those that change or stop
// an instance have their own.
class Demo : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!install_once().empty()) return;
    demo_ = new Instance("demo", demo_yaml());
    start_ = new Shell(demo_->systemctl("start"));
    // At once: a unit that said it was ready before the loop ran would be caught starting.
    answer_ = new json(ctl_status("demo", "", &status_raw_));
  }
  static void TearDownTestSuite() {
    delete demo_;
    delete start_;
    delete answer_;
  }
  void SetUp() override {
    ASSERT_EQ(install_once(), "") << "installing as a user does";
    ASSERT_EQ(start_->status, 0) << start_->out << demo_->journal();
  }
  static Instance* demo_;
  static Shell* start_;
  static Shell status_raw_;
  static json* answer_;
};
Instance* Demo::demo_ = nullptr;
Shell* Demo::start_ = nullptr;
Shell Demo::status_raw_;
json* Demo::answer_ = nullptr;

TEST_F(Demo, SystemctlStartReturnsOnlyOnceTheServoRuns) {
  ASSERT_TRUE(answer_->is_object()) << status_raw_.out;
  const json& s = (*answer_)["status"];
  EXPECT_EQ(s["state"], "running") << s.dump();
  EXPECT_GE(s["tick"].get<long>(), 1) << "READY=1 follows the first tick";
  EXPECT_TRUE(s["device"]["output_enabled"].get<bool>()) << s.dump();
  EXPECT_EQ(demo_->property("ActiveState"), "active");
  EXPECT_EQ(demo_->property("StatusText"), "servo running at 100 Hz");
}

TEST_F(Demo, TheLoopThreadRunsSchedFifoAtTheConfiguredPriorityLockedAsUserHapticd) {
  const pid_t pid = demo_->main_pid();
  ASSERT_GT(pid, 0);
  const passwd* user = getpwnam("hapticd");
  ASSERT_NE(user, nullptr);
  const std::string uids = proc_status(pid, "Uid");  // real, effective, saved, file system
  EXPECT_EQ(uids.substr(0, uids.find('\t')), std::to_string(user->pw_uid)) << uids;
  int fifo = 0;
  for (const ThreadInfo& t : threads_of(pid)) {
    if (t.policy != SCHED_FIFO) continue;
    ++fifo;
    EXPECT_EQ(t.comm, "hapticd-rt");
    EXPECT_EQ(t.priority, 70) << "loop.rt_priority";
  }
  EXPECT_EQ(fifo, 1) << "one SCHED_FIFO thread, the loop's";
  const std::string locked = proc_status(pid, "VmLck");
  EXPECT_GT(std::stol("0" + locked), 1000) << "mlockall: VmLck " << locked;
  EXPECT_TRUE(contains(demo_->wait_journal("rt: SCHED_FIFO"),
                       "rt: SCHED_FIFO 70, memory locked, cpu_dma_latency 0"))
      << demo_->journal();
}

TEST_F(Demo, TheControlSocketServesRootAndGroupHapticdAndNobodyElse) {
  Shell root, member, stranger;
  EXPECT_EQ(ctl_status("demo", "", &root)["status"]["state"], "running") << root.out;
  EXPECT_EQ(ctl_status("demo", kOperator, &member)["status"]["state"], "running") << member.out;
  EXPECT_TRUE(ctl_status("demo", kStranger, &stranger).is_null()) << stranger.out;
  EXPECT_NE(stranger.status, 0);
  EXPECT_TRUE(contains(stranger.out, "ermission denied")) << stranger.out;
  // As people type it.
  const Shell text = sh_as(kOperator, "hapticctl -i demo status");
  EXPECT_EQ(text.status, 0) << text.out;
  EXPECT_TRUE(contains(text.out, "hapticd running: sim at 100 Hz (realtime)")) << text.out;
}

TEST_F(Demo, EventsCarryTheirPriorityIntoTheJournal) {
  demo_->wait_journal("rt: SCHED_FIFO");
  const std::string warnings = demo_->journal("warning");
  EXPECT_TRUE(contains(warnings, "[warning] gate: device.max_force = 2 N saturates the wall"))
      << warnings;
  EXPECT_FALSE(contains(warnings, "output enabled")) << "an info line among the warnings";
  EXPECT_FALSE(contains(warnings, "gate: pass")) << warnings;
  const std::string info = demo_->journal("info");
  EXPECT_TRUE(contains(info, "[info] output enabled: sim")) << info;
  EXPECT_FALSE(contains(info, "<6>")) << "journald took the prefix as the priority";
}

TEST_F(Demo, SystemdAnalyzeRatesTheRunningUnitsExposureAtMostTwo) {
  Shell r;
  const double level = exposure(demo_->unit(), &r);
  EXPECT_GE(level, 0.0) << r.out;
  EXPECT_LE(level, 2.0) << r.out;
  RecordProperty("exposure", std::to_string(level));
}

class OwnDemo : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(install_once(), "") << "installing as a user does"; }
};

TEST_F(OwnDemo, ReloadAppliesAChangedWallAndARefusedOneLeavesTheOldWallAndSaysWhy) {
  Instance reload("reload", demo_yaml("250"));
  ASSERT_EQ(reload.systemctl("start").status, 0) << reload.journal();
  reload.write_config(demo_yaml("300"));
  const Shell ok = reload.systemctl("reload");
  EXPECT_EQ(ok.status, 0) << ok.out << reload.journal();
  // `systemctl reload` returns once the loop has taken it: nothing to wait for.
  EXPECT_EQ(ctl_status("reload", "")["status"]["wall"]["stiffness"], 300);
  const std::regex applied(
      "reload from /etc/hapticd/reload.yaml accepted: wall K 300 N/m "
      "B 0.2 N s/m from tick [0-9]+");
  EXPECT_TRUE(std::regex_search(reload.journal(), applied)) << reload.journal();

  reload.write_config(demo_yaml("1000"));  // b_req 5.2 N s/m at 100 Hz: refused
  const Shell refused = reload.systemctl("reload");
  EXPECT_NE(refused.status, 0) << "systemctl reload says it failed";
  EXPECT_TRUE(contains(refused.out, "hapticd@reload.service failed")) << refused.out;
  EXPECT_EQ(reload.property("ActiveState"), "active") << "the servo runs on";
  EXPECT_EQ(ctl_status("reload", "")["status"]["wall"]["stiffness"], 300) << "the old wall";
  const std::string why = reload.journal("warning");
  EXPECT_TRUE(contains(why,
                       "reload from /etc/hapticd/reload.yaml refused: the gate refuses it: "
                       "passivity: required damping b_req = 5.2 N s/m exceeds"))
      << why;
}

// Also the excerpts docs/operations.md shows, printed to the test's log.
TEST_F(OwnDemo, StopEndsWithZeroForceExit0TheSummaryInTheJournalAndAReadableTickLog) {
  Instance demo("demo", demo_yaml());
  // For the excerpt as a user reads it: this unit's journal from now on (the suite's own
  // hapticd@demo ended tests ago).
  std::string since = sh("date +@%s").out;
  since.erase(since.find_last_not_of('\n') + 1);
  ASSERT_EQ(demo.systemctl("start").status, 0) << demo.journal();
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));  // through the press and back
  std::cout << "$ systemctl status hapticd@demo\n" << demo.systemctl("status").out << "\n";
  const Shell stop = demo.systemctl("stop");
  EXPECT_EQ(stop.status, 0) << stop.out;
  // The unit is unloaded once stopped (its properties with it): systemd's word is the journal's.
  const std::string j = demo.wait_journal("Deactivated successfully");
  std::cout << "$ journalctl -u hapticd@demo\n"
            << sh("journalctl --no-pager -u hapticd@demo --since=" + since).out << "\n";
  EXPECT_TRUE(contains(j, "hapticd@demo.service: Deactivated successfully.")) << j;
  EXPECT_FALSE(contains(j, "Main process exited")) << "logged for any exit but 0";
  EXPECT_TRUE(contains(j, "SIGTERM received: stopping")) << j;
  EXPECT_TRUE(contains(j, "stopped by signal SIGTERM")) << j;
  EXPECT_TRUE(contains(j, "output         sim configured, disabled, last command 0 N")) << j;
  EXPECT_TRUE(contains(j, "faults         none")) << j;
  std::smatch ticks;
  ASSERT_TRUE(std::regex_search(j, ticks, std::regex("hapticd run: ([0-9]+) ticks"))) << j;

  // The tick log, as an operator in group hapticd reads it (not others: UMask 0027).
  const std::string log = "/var/lib/hapticd/demo/ticks.hlog";
  const Shell csv = sh_as(kOperator, "hapticd export " + log);
  ASSERT_EQ(csv.status, 0) << csv.out;
  const long rows = std::count(csv.out.begin(), csv.out.end(), '\n') - 1;  // less the header
  EXPECT_EQ(rows, std::stol(ticks[1])) << "one record a tick";
  EXPECT_NE(sh_as(kStranger, "hapticd export " + log).status, 0) << "readable by others";
}

}  // namespace
}  // namespace hapticd::systemd_test
