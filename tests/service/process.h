// Runs the hapticd binary the way a user does, for end-to-end tests.
#pragma once

#include <sys/types.h>

#include <string>
#include <string_view>
#include <vector>

namespace hapticd::testing {

struct ProcessResult {
  int exit_code = -1;  // -1 if killed by a signal
  std::string out;
  std::string err;
};

// Runs `args` (args[0] is the program) to completion; `env` entries "K=V" are added.
ProcessResult run_process(const std::vector<std::string>& args,
                          const std::vector<std::string>& env = {});

// The same with standard output opened on `stdout_path` (e.g. /dev/full) instead of a pipe;
// ProcessResult::out stays empty.
ProcessResult run_process_with_stdout(const std::vector<std::string>& args,
                                      const std::string& stdout_path);

// A process started in the background; wait() collects it like run_process.
class BackgroundProcess {
 public:
  BackgroundProcess(const std::vector<std::string>& args, const std::vector<std::string>& env = {});
  ~BackgroundProcess();
  void signal(int sig) const;
  ProcessResult wait();
  pid_t pid() const { return pid_; }
  // Waits (up to `timeout_ms`) until the program started (after its exec) blocks `sig`: from
  // then on a signal cannot kill it, which is when a test may send one. False on time-out or
  // exit.
  bool wait_until_blocked(int sig, int timeout_ms = 5000) const;
  // Closes the read ends of its stdout and stderr pipes, as `| head` does when it is done.
  void close_output();

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
  int err_fd_ = -1;
  std::string comm_;  // the program's name as /proc/PID/status shows it after its exec
};

// A systemd notify socket the daemon reports to (pass env() to the process): a test waits
// for READY=1 (output enabled, the RT thread running) instead of guessing with a sleep.
class NotifySocket {
 public:
  NotifySocket();
  ~NotifySocket();
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;
  std::string env() const { return "NOTIFY_SOCKET=" + path_; }
  // Waits up to `timeout_ms` for a message containing `text`; false on time-out. The default
  // is a deadline for a daemon that never gets there: under ThreadSanitizer on a loaded
  // 2-core machine a start-up took over 10 s.
  bool wait_for(const std::string& text, int timeout_ms = 30000);

 private:
  std::string path_;
  int fd_ = -1;
};

// Waits (up to 30 s) for `p` to report READY=1 on `notify`: "" when it did; otherwise `p` is
// killed and the answer says how it ended and what it printed, so a failed start names its
// cause instead of a bare time-out.
std::string wait_ready(NotifySocket& notify, BackgroundProcess& p);

std::string hapticd_binary();                  // path of the built daemon
std::string source_dir();                      // the project root
std::string example(const std::string& name);  // the shipped config/<name>
std::string coupling_example();  // config/coupling-example.yaml (Example 1 of the paper)
std::string build_dir();         // the build tree the tests belong to
std::string temp_path(const std::string& name);  // a fresh path under the test's temp dir
std::string read_file(const std::string& path);
// Writes `text` to temp_path(name) whole (renamed into place, as an editor saves): its path.
std::string write_temp(const std::string& name, const std::string& text);
// Whether `text` (a command's output, a file) holds `part`.
inline bool has(std::string_view text, std::string_view part) {
  return text.find(part) != std::string_view::npos;
}

}  // namespace hapticd::testing
