#include "systemd_rig.h"

#include <grp.h>
#include <sched.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

namespace hapticd::systemd_test {
namespace {

// 'text' for /bin/sh.
std::string quote(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  std::size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

// The journal's current end, so an instance reads only what was written after it began.
std::string journal_cursor() {
  const Shell s = sh("journalctl --no-pager -q -n 0 --show-cursor");
  const std::size_t at = s.out.find("-- cursor: ");
  return at == std::string::npos ? "" : trim(s.out.substr(at + 11));
}

std::string install_steps() {
  const std::string build = HAPTICD_BUILD_DIR;
  const std::vector<std::string> steps = {
      "cmake --install " + quote(build) + " --prefix /usr",
      "systemd-sysusers",
      "udevadm control --reload",
      "udevadm trigger --action=add --subsystem-match=misc --sysname-match=cpu_dma_latency && "
      "udevadm settle --timeout=60",
      "systemctl daemon-reload",
      std::string("id ") + kOperator + " >/dev/null 2>&1 || useradd --system --no-create-home " +
          "--shell /usr/sbin/nologin --groups hapticd " + kOperator,
      std::string("id ") + kStranger + " >/dev/null 2>&1 || useradd --system --no-create-home " +
          "--shell /usr/sbin/nologin " + kStranger};
  for (const std::string& step : steps) {
    const Shell r = sh(step);
    if (r.status != 0) {
      return "`" + step + "` failed with status " + std::to_string(r.status) + ":\n" + r.out;
    }
  }
  const group* g = getgrnam("hapticd");
  struct stat st {};
  if (g == nullptr) return "systemd-sysusers made no group hapticd";
  if (stat("/dev/cpu_dma_latency", &st) != 0 || st.st_gid != g->gr_gid) {
    return "the installed udev rule did not give group hapticd /dev/cpu_dma_latency";
  }
  return "";
}

void set_path(YAML::Node node, const std::vector<std::string>& keys, std::size_t i,
              const YAML::Node& value) {
  if (i + 1 == keys.size()) {
    node[keys[i]] = value;
    return;
  }
  set_path(node[keys[i]], keys, i + 1, value);
}

}  // namespace

Shell sh(const std::string& command) {
  const auto t0 = std::chrono::steady_clock::now();
  Shell r;
  FILE* p = ::popen(("exec 2>&1; " + command).c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = ::pclose(p);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (std::getenv("HAPTICD_SYSTEMD_TRACE") != nullptr) {
    std::fprintf(stderr, "[trace %5lld ms] %s\n",
                 static_cast<long long>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                            std::chrono::steady_clock::now() - t0)
                                            .count()),
                 command.substr(0, 100).c_str());
  }
  return r;
}

Shell sh_as(const std::string& user, const std::string& command) {
  return sh("runuser -u " + user + " -- /bin/sh -c " + quote(command));
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

const std::string& install_once() {
  static const std::string error = install_steps();
  return error;
}

std::string config_text(const std::string& example, const std::vector<std::string>& sets) {
  YAML::Node root = YAML::LoadFile(std::string(HAPTICD_SOURCE_DIR) + "/config/" + example);
  for (const std::string& s : sets) {
    const std::size_t eq = s.find('=');
    std::vector<std::string> keys;
    std::stringstream path(s.substr(0, eq));
    for (std::string k; std::getline(path, k, '.');) keys.push_back(k);
    set_path(root, keys, 0, YAML::Load(s.substr(eq + 1)));
  }
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
}

std::vector<std::string> guest_sets(std::vector<std::string> more) {
  // The emulated machine's transfers can answer the direction check's pulse 300 ms late.
  std::vector<std::string> s = {"loop.rate_hz=100", "loop.overrun_fault_streak=1000",
                                "safety.direction_check.max_latency_ms=300"};
  s.insert(s.end(), more.begin(), more.end());
  return s;
}

Instance::Instance(std::string name, const std::string& yaml)
    : name_(std::move(name)), cursor_(journal_cursor()) {
  write_config(yaml);
}

Instance::~Instance() {
  sh("systemctl stop " + unit() + "; systemctl reset-failed " + unit());
  std::filesystem::remove(config_path());
}

void Instance::write_config(const std::string& yaml) const { std::ofstream(config_path()) << yaml; }

Shell Instance::systemctl(const std::string& verb) const {
  return sh("systemctl --no-pager " + verb + " " + unit());
}

std::string Instance::property(const std::string& name) const {
  return trim(sh("systemctl show -p " + name + " --value " + unit()).out);
}

pid_t Instance::main_pid() const {
  return static_cast<pid_t>(std::stol("0" + property("MainPID")));
}

std::vector<nlohmann::json> Instance::entries() const {
  // Read whole and filtered here: journalctl --after-cursor with matches skips the first
  // matching entry when the cursor's own entry does not match.
  std::stringstream lines(
      sh("journalctl --sync && journalctl --no-pager -q -o json --after-cursor=" + quote(cursor_))
          .out);
  std::vector<nlohmann::json> mine;
  for (std::string line; std::getline(lines, line);) {
    auto e = nlohmann::json::parse(line, nullptr, false);
    if (!e.is_object() || !e["MESSAGE"].is_string()) continue;
    if (e.value("_SYSTEMD_UNIT", "") == unit() || e.value("UNIT", "") == unit()) {
      mine.push_back(std::move(e));
    }
  }
  return mine;
}

std::string Instance::journal(const std::string& priority) const {
  static const std::vector<std::string> kNames = {"emerg",   "alert",  "crit", "err",
                                                  "warning", "notice", "info", "debug"};
  const auto named = std::find(kNames.begin(), kNames.end(), priority);
  const int most = priority.empty() ? 7 : static_cast<int>(named - kNames.begin());
  std::string text;
  for (const nlohmann::json& e : entries()) {
    if (std::stoi(e.value("PRIORITY", "6")) <= most) text += e["MESSAGE"].get<std::string>() + "\n";
  }
  return text;
}

std::string Instance::wait_journal(const std::string& text,
                                   std::chrono::milliseconds timeout) const {
  const auto end = std::chrono::steady_clock::now() + timeout;
  std::string j = journal();
  while (!contains(j, text) && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    j = journal();
  }
  return j;
}

unsigned long long Instance::journal_monotonic_us(const std::string& text) const {
  for (const nlohmann::json& e : entries()) {
    if (contains(e["MESSAGE"].get<std::string>(), text)) {
      return std::stoull(e["__MONOTONIC_TIMESTAMP"].get<std::string>());
    }
  }
  return 0;
}

std::string Instance::wait_inactive(std::chrono::milliseconds timeout) const {
  const auto end = std::chrono::steady_clock::now() + timeout;
  std::string state = property("ActiveState");
  while ((state == "active" || state == "activating" || state == "deactivating" ||
          state == "reloading") &&
         std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    state = property("ActiveState");
  }
  return state;
}

std::vector<ThreadInfo> threads_of(pid_t pid) {
  std::vector<ThreadInfo> threads;
  std::error_code ec;
  for (const auto& e :
       std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
    ThreadInfo t;
    t.tid = static_cast<pid_t>(std::stol(e.path().filename().string()));
    std::ifstream(e.path() / "comm") >> t.comm;
    t.policy = sched_getscheduler(t.tid);
    sched_param p{};
    if (sched_getparam(t.tid, &p) == 0) t.priority = p.sched_priority;
    threads.push_back(t);
  }
  return threads;
}

std::string proc_status(pid_t pid, const std::string& field) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(field + ":", 0) == 0) return trim(line.substr(field.size() + 1));
  }
  return "";
}

unsigned long long monotonic_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<unsigned long long>(ts.tv_sec) * 1'000'000ull +
         static_cast<unsigned long long>(ts.tv_nsec) / 1000;
}

double exposure(const std::string& unit, Shell* raw) {
  const Shell r = sh("systemd-analyze security --no-pager " + unit);
  if (raw != nullptr) *raw = r;
  const std::string key = "Overall exposure level for " + unit + ": ";
  const std::size_t at = r.out.find(key);
  return at == std::string::npos ? -1.0 : std::stod(r.out.substr(at + key.size()));
}

}  // namespace hapticd::systemd_test
