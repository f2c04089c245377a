// Signals against a running daemon (issue 7): none may end `run` with output enabled. Each
// run is checked the way the operator would: exit code, the summary's account of the device's
// final state, and a log that reads back whole.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

// What every ended run must show, whatever ended it.
void expect_safe_end(const std::string& summary_path, const std::string& log_path) {
  const json s = json::parse(read_file(summary_path));
  EXPECT_EQ(s["device"]["final_command"].get<double>(), 0.0) << s.dump();
  EXPECT_FALSE(s["device"]["output_enabled"].get<bool>()) << s.dump();
  if (!log_path.empty()) {
    const telemetry::LogContents c = telemetry::read_log(log_path);
    EXPECT_EQ(c.records.size(), s["ticks"].get<std::size_t>());
    EXPECT_TRUE(c.trailing_reason.empty()) << c.trailing_reason;
  }
}

struct Named {
  int sig;
  const char* name;
};

TEST(CliSignals, EveryTerminatingSignalStopsTheRunLikeSigterm) {
  // SIGHUP is not among them: it reloads the configuration (CliSignals.SighupReloads...).
  const Named stops[] = {{SIGINT, "SIGINT"},     {SIGQUIT, "SIGQUIT"},     {SIGUSR1, "SIGUSR1"},
                         {SIGUSR2, "SIGUSR2"},   {SIGALRM, "SIGALRM"},     {SIGVTALRM, "SIGVTALRM"},
                         {SIGPROF, "SIGPROF"},   {SIGTRAP, "SIGTRAP"},     {SIGABRT, "SIGABRT"},
                         {SIGXCPU, "SIGXCPU"},   {SIGIO, "SIGPOLL"},       {SIGPWR, "SIGPWR"},
                         {SIGTSTP, "SIGTSTP"},   {SIGSTKFLT, "SIGSTKFLT"}, {SIGRTMIN, "SIGRTMIN"},
                         {SIGRTMAX, "SIGRTMIN+"}};
  for (const Named& n : stops) {
    SCOPED_TRACE(n.name);
    const std::string tag = std::to_string(n.sig);
    const std::string log = temp_path("sig" + tag + ".hlog"),
                      sum = temp_path("sig" + tag + ".json");
    NotifySocket notify;
    BackgroundProcess p(
        {hapticd_binary(), "run", "--duration", "10", "--log", log, "--summary-json", sum},
        {notify.env()});
    ASSERT_EQ(wait_ready(notify, p), "");
    p.signal(n.sig);
    const ProcessResult r = p.wait();
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json s = json::parse(read_file(sum));
    EXPECT_EQ(s["stop_reason"].get<std::string>().rfind(std::string("signal ") + n.name, 0), 0u)
        << s["stop_reason"];
    EXPECT_TRUE(s["output_was_enabled"].get<bool>());
    EXPECT_GT(s["ticks"].get<int>(), 0);
    expect_safe_end(sum, log);
  }
}

// SIGHUP reloads the file the run was started with; the embedded default has none, so the
// run says so and goes on to the end of its duration.
TEST(CliSignals, SighupReloadsAndNeverStopsTheRun) {
  const std::string sum = temp_path("hup.json"), log = temp_path("hup.hlog");
  NotifySocket notify;
  BackgroundProcess p({hapticd_binary(), "run", "--duration", "1.5", "--log", log, "--summary-json",
                       sum, "--set", "loop.overrun_fault_streak=1000000000"},
                      {notify.env()});
  ASSERT_EQ(wait_ready(notify, p), "");
  p.signal(SIGHUP);
  const ProcessResult r = p.wait();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("SIGHUP"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nothing to reload"), std::string::npos) << r.err;
  const json s = json::parse(read_file(sum));
  EXPECT_EQ(s["stop_reason"], "duration");
  EXPECT_EQ(s["ticks"], 1500);
  expect_safe_end(sum, log);
}

TEST(CliSignals, SignalsWhoseOnlyHarmIsTheirDefaultAreIgnored) {
  const std::string sum = temp_path("ignored.json");
  NotifySocket notify;
  BackgroundProcess p({hapticd_binary(), "run", "--duration", "10", "--summary-json", sum},
                      {notify.env()});
  ASSERT_EQ(wait_ready(notify, p), "");
  for (int sig : {SIGPIPE, SIGXFSZ, SIGTTIN, SIGTTOU}) p.signal(sig);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  p.signal(SIGTERM);
  const ProcessResult r = p.wait();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(read_file(sum))["stop_reason"], "signal SIGTERM");
  expect_safe_end(sum, "");
}

// `hapticd run 2>&1 | head -n 3`, then SIGTERM: the stop's log line hits a closed pipe. That
// used to kill the process with SIGPIPE (exit 141) and output enabled.
TEST(CliSignals, AClosedOutputPipeDoesNotKillTheRun) {
  const std::string sum = temp_path("pipe.json");
  NotifySocket notify;
  BackgroundProcess p({hapticd_binary(), "run", "--duration", "10", "--summary-json", sum},
                      {notify.env()});
  ASSERT_EQ(wait_ready(notify, p), "");
  p.close_output();
  p.signal(SIGTERM);
  const ProcessResult r = p.wait();
  EXPECT_EQ(r.exit_code, 1) << "the summary could not be printed: a failure, not a crash";
  const json s = json::parse(read_file(sum));
  EXPECT_EQ(s["stop_reason"], "signal SIGTERM");
  expect_safe_end(sum, "");
}

// A stop requested while the gate still analyses (a long delay makes that take a while)
// used to be held until the supervisor started, after output had been enabled.
TEST(CliSignals, AStopDuringStartUpNeverEnablesOutput) {
  const std::string log = temp_path("early.hlog"), sum = temp_path("early.json");
  BackgroundProcess p({hapticd_binary(), "run", "--set", "wall.delay_samples=100", "--set",
                       "safety.gate=warn", "--log", log, "--summary-json", sum});
  ASSERT_TRUE(p.wait_until_blocked(SIGTERM));
  p.signal(SIGTERM);
  const ProcessResult r = p.wait();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("output enabled"), std::string::npos) << r.err;
  const json s = json::parse(read_file(sum));
  EXPECT_FALSE(s["output_was_enabled"].get<bool>());
  EXPECT_EQ(s["ticks"], 0);
  EXPECT_EQ(s["stop_reason"], "signal SIGTERM");
  EXPECT_NE(r.out.find("stopped by signal SIGTERM before output was enabled"), std::string::npos)
      << r.out;
  expect_safe_end(sum, "");
}

}  // namespace
}  // namespace hapticd::testing
