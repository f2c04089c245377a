// What the tests under a real systemd share (tests/systemd, run in the systemd boot of the
// kernel test machine, `tools/kernel-vm/run --systemd`): hapticd installed as a user installs
// it, instances of hapticd@.service written and started, their journal, their process.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hapticd::systemd_test {

struct Shell {
  int status = -1;  // the exit status; 128 + N when killed by signal N
  std::string out;  // standard output and standard error, interleaved
};

// `command` run by /bin/sh, as root (the tests' own user in the machine).
Shell sh(const std::string& command);
// `command` run by /bin/sh as `user` (runuser: its own groups, from the group database).
Shell sh_as(const std::string& user, const std::string& command);
bool contains(const std::string& text, const std::string& part);

// Once per process: `cmake --install BUILD --prefix /usr`, `systemd-sysusers`, the installed
// udev rule applied, `systemctl daemon-reload`, and two users to ask the control socket:
// kOperator (in group hapticd) and kStranger (not). "" when all of it worked, else what failed.
const std::string& install_once();
inline const char* const kOperator = "hapticd-operator";
inline const char* const kStranger = "hapticd-stranger";

// config/EXAMPLE of the source tree with `sets` ("key.path=value", the value in YAML) applied,
// as YAML text for /etc/hapticd/NAME.yaml (the unit takes no --set).
std::string config_text(const std::string& example, const std::vector<std::string>& sets);

// What the machine sustains: qemu without KVM on a loaded 2-core host stalls for tens of
// milliseconds now and then, so the loop runs at 100 Hz with a wall the gate passes there and
// tolerates the emulator's late wake-ups (as the kernel tests do).
std::vector<std::string> guest_sets(std::vector<std::string> more = {});

// hapticd@NAME: its configuration in /etc/hapticd/NAME.yaml while it exists; stopped, its
// failure state reset and its files removed at the end.
class Instance {
 public:
  Instance(std::string name, const std::string& yaml);
  ~Instance();
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;

  const std::string& name() const { return name_; }
  std::string unit() const { return "hapticd@" + name_ + ".service"; }
  std::string config_path() const { return "/etc/hapticd/" + name_ + ".yaml"; }
  void write_config(const std::string& yaml) const;

  Shell systemctl(const std::string& verb) const;       // `systemctl VERB hapticd@NAME.service`
  std::string property(const std::string& name) const;  // `systemctl show -p NAME --value`
  pid_t main_pid() const;
  // The journal of the unit's current (or last) invocation, its own lines and systemd's lines
  // about it, as `journalctl -o cat`; `priority` as journalctl -p takes it ("" for all).
  std::string journal(const std::string& priority = "") const;
  // Waits (up to `timeout`) until that journal contains `text`; the journal either way.
  std::string wait_journal(const std::string& text,
                           std::chrono::milliseconds timeout = std::chrono::seconds(20)) const;
  // The journal entry's __MONOTONIC_TIMESTAMP (us since boot) of the first line with `text`;
  // 0 when there is none.
  unsigned long long journal_monotonic_us(const std::string& text) const;
  // Its journal entries (journalctl's JSON objects), in order.
  std::vector<nlohmann::json> entries() const;
  // Waits until the unit is no longer active or activating/deactivating; its ActiveState.
  std::string wait_inactive(std::chrono::milliseconds timeout = std::chrono::seconds(30)) const;

 private:
  std::string name_;
  std::string cursor_;  // the journal's end when the instance was made: its journal follows
};

// A thread of a process, as /proc and the scheduler report it.
struct ThreadInfo {
  pid_t tid = 0;
  std::string comm;
  int policy = -1;  // SCHED_OTHER, SCHED_FIFO, ...
  int priority = 0;
};
std::vector<ThreadInfo> threads_of(pid_t pid);
// A field of /proc/PID/status ("Uid", "VmLck", ...), its text after the colon, trimmed.
std::string proc_status(pid_t pid, const std::string& field);
unsigned long long monotonic_us();  // CLOCK_MONOTONIC, as the journal's monotonic stamps
// `systemd-analyze security UNIT`'s overall exposure level; -1 when it gives none.
double exposure(const std::string& unit, Shell* raw = nullptr);

}  // namespace hapticd::systemd_test
