// A `hapticd run` with a control socket, for the end-to-end tests of the socket, hapticctl and
// live reload: started in the background, ready once READY=1 arrived (output enabled, the RT
// thread running), asked through the built hapticctl or through a raw socket.
#pragma once

#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "process.h"

namespace hapticd::testing {

std::string hapticctl_binary();

// A full configuration for the sim (reloads send whole files): a hand holding the device
// 10 mm inside an undamped wall of stiffness `k` (so in steady contact f = K p exactly).
// `loop` and `wall` are more lines of those sections. The loop tolerates any overrun streak:
// a loaded test machine must not fault a test about something else.
std::string pressing_config(double k, const std::string& loop = "", const std::string& wall = "");

class Daemon {
 public:
  // Starts `hapticd run --socket ... --log ... --summary-json ... ARGS` in `dir` ("" for a
  // test temp dir) and waits for READY=1; ready() says whether it came. It tolerates any
  // overrun streak (--set loop.overrun_fault_streak, the value pressing_config() has too).
  explicit Daemon(const std::vector<std::string>& args, const std::string& dir = "");
  ~Daemon();  // stops a daemon still running (SIGTERM) and collects it

  bool ready() const { return ready_; }
  const std::string& socket() const { return socket_; }
  const std::string& log() const { return log_; }
  const std::string& summary() const { return summary_; }
  pid_t pid() const { return process_->pid(); }
  void signal(int sig) const { process_->signal(sig); }

  // hapticctl --socket S ARGS.
  ProcessResult ctl(const std::vector<std::string>& args) const;
  // hapticctl --socket S --json status, parsed: its "status" member (null if it failed).
  nlohmann::json status() const;
  // Polls status until `pred` holds (up to about 20 s of polls); the last status.
  template <typename Pred>
  nlohmann::json wait_status(Pred pred) const;
  // Waits for the daemon to exit (after a stop) and returns what it printed.
  ProcessResult wait();

 private:
  std::string socket_, log_, summary_;
  NotifySocket notify_;
  std::unique_ptr<BackgroundProcess> process_;
  bool ready_ = false;
  bool collected_ = false;
};

// One connection to a control socket, raw: for what hapticctl never sends.
class RawClient {
 public:
  explicit RawClient(const std::string& socket);  // connected; throws on failure
  ~RawClient();
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;
  // Sends all of `bytes`; false when the daemon closed the connection (EPIPE, ECONNRESET).
  bool send(const std::string& bytes) const;
  // The next line (without its newline), "" when the connection ended first or after
  // `timeout_ms` without one.
  std::string line(int timeout_ms = 20000);
  // True when the daemon closed the connection (within `timeout_ms`).
  bool closed_by_peer(int timeout_ms = 20000);
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  std::string in_;
};

template <typename Pred>
nlohmann::json Daemon::wait_status(Pred pred) const {
  nlohmann::json s;
  for (int i = 0; i < 2000; ++i) {
    s = status();
    if (!s.is_null() && pred(s)) return s;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return s;
}

}  // namespace hapticd::testing
