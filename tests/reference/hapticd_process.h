// `hapticd run` as a user runs it, in its own process, for the reference-device tests of every
// transport: its exit status, its --summary-json and its log. Only the binary is used, never a
// header of it.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

namespace hapticd::reference {

struct HapticdRun {
  int status = -1;  // exit status, 128 + signal when killed
  nlohmann::json summary;
  std::string log;
  std::string faults() const {
    return summary.is_object() ? summary.value("faults", nlohmann::json::array()).dump()
                               : "(no summary: exit " + std::to_string(status) + ")";
  }
};

// config/NAME of the source tree.
inline std::string shipped(const std::string& name) {
  return std::string(HAPTICD_SOURCE_DIR) + "/config/" + name;
}

// The log (stderr, written line by line) of the hapticd run_hapticd runs now, for `during`.
inline std::string& running_log() {
  static std::string path;
  return path;
}

// Runs `hapticd ARGS... --summary-json FILE` (HAPTICD_BINARY); `during(pid)` runs while it
// does, then the process is waited for. The HID driver's kernel tests use it too. `under`, when
// given, is a program (with its arguments) that runs hapticd, such as strace.
inline HapticdRun run_hapticd(std::vector<std::string> args,
                              const std::function<void(pid_t)>& during = {},
                              std::vector<std::string> under = {}) {
  static int n = 0;
  const std::string stem =
      "/tmp/hapticd-kt-" + std::to_string(::getpid()) + "-" + std::to_string(n++);
  args.insert(args.begin(), HAPTICD_BINARY);
  args.insert(args.begin(), under.begin(), under.end());
  args.insert(args.end(), {"--summary-json", stem + ".json"});
  running_log() = stem + ".err";
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (!std::freopen((stem + ".err").c_str(), "w", stderr) ||
        !std::freopen("/dev/null", "w", stdout))
      _exit(127);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    _exit(127);
  }
  if (during) during(pid);
  int st = 0;
  ::waitpid(pid, &st, 0);
  HapticdRun r;
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  std::ifstream j(stem + ".json");
  if (j) r.summary = nlohmann::json::parse(j, nullptr, false);
  std::ifstream e(stem + ".err");
  r.log.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

// `hapticd run --config CONFIG --set S... ARGS...` (under `under`, when given).
inline HapticdRun run_hapticd(const std::string& config, const std::vector<std::string>& sets,
                              std::vector<std::string> args,
                              const std::function<void(pid_t)>& during = {},
                              std::vector<std::string> under = {}) {
  std::vector<std::string> all = {"run", "--config", config};
  for (const std::string& s : sets) all.insert(all.end(), {"--set", s});
  all.insert(all.end(), args.begin(), args.end());
  return run_hapticd(std::move(all), during, std::move(under));
}

// Waits up to `timeout` for `done`; false if it never held.
inline bool wait_until(const std::function<bool()>& done,
                       std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

// Until the running hapticd's direction check has armed the wall (its log line: confirmed, or
// unchecked where the test allows it), or `timeout`;
// false then. A hand that pushes before it keeps the device from the rest the check waits for,
// and a fault struck before it is the check's, not the wall's: a user acts once the log says so.
// A fault ends the wait at once (false).
inline bool wait_armed(std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
  bool armed = false;
  wait_until(
      [&] {
        std::ifstream log(running_log());
        const std::string text{std::istreambuf_iterator<char>(log), {}};
        armed = text.find("direction check: confirmed") != std::string::npos ||
                text.find("the wall is armed UNCHECKED") != std::string::npos;
        return armed || text.find("] fault: ") != std::string::npos;
      },
      timeout);
  return armed;
}

// Until the running hapticd has enabled output (its log line "output enabled"), or `timeout`;
// false then, or at once on a fault. A hand that pushes the device into a wall before it is
// enabled finds the wall unarmed (a wall the device starts inside acts once it is left).
inline bool wait_enabled(std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  bool enabled = false;
  wait_until(
      [&] {
        std::ifstream log(running_log());
        const std::string text{std::istreambuf_iterator<char>(log), {}};
        enabled = text.find("output enabled") != std::string::npos;
        return enabled || text.find("] fault: ") != std::string::npos;
      },
      timeout);
  return enabled;
}

// Whether process `pid` (a child) has ended, without reaping it.
inline bool ended(pid_t pid) {
  siginfo_t info{};
  return ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 &&
         info.si_pid == pid;
}

}  // namespace hapticd::reference
