// What the loop's thread asks of the kernel each tick, read from `strace -ff -T` of a hapticd
// run (one file per thread): the thread that sleeps in clock_nanosleep most is the loop's
// (hapticd-rt), and its system calls between two of those sleeps are one tick's. The evdev
// driver's EVIOCSFF is made by its update thread (hapticd-evout), counted apart over the
// loop's ticks. For the BENCHMARKS.md table of each driver class, and the tests that hold the
// evdev driver to one read-and-update a tick.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace hapticd::reference {

// `strace -ff -T -qq -o PREFIX` (PREFIX.TID for each thread): what run_hapticd runs hapticd
// under. An earlier run's PREFIX.* are removed first: tick_calls reads every file of the
// prefix, and a test's second run in the guest (tools/kernel-vm/test-suite) would otherwise
// count the first run's threads with its own.
inline std::vector<std::string> strace_to(const std::string& prefix) {
  const std::filesystem::path p(prefix);
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(p.parent_path(), ec)) {
    if (e.path().filename().string().rfind(p.filename().string() + ".", 0) == 0) {
      std::filesystem::remove(e.path(), ec);
    }
  }
  return {"/usr/bin/strace", "-ff", "-T", "-qq", "-o", prefix};
}

struct TickCalls {
  long ticks = 0;                          // sleeps of the loop's thread, steady state
  std::map<std::string, double> per_tick;  // "read", "futex", ...: calls a tick
  double sff_elsewhere_per_tick = 0.0;     // EVIOCSFF on the other threads, per loop tick
  double evioc_sff_us_median = 0.0;        // time in one EVIOCSFF (strace -T), any thread
};

// Reads PREFIX.*; `skip` ticks at each end are left out (start-up and shut-down).
inline TickCalls tick_calls(const std::string& prefix, long skip = 20) {
  struct Call {
    std::string name;
    double seconds;
  };
  std::map<std::string, std::vector<Call>> by_thread;
  const std::regex line(R"(^([a-z_0-9]+)\((.*)\)\s+=.*<([0-9.]+)>$)");
  const std::filesystem::path p(prefix);
  for (const auto& e : std::filesystem::directory_iterator(p.parent_path())) {
    const std::string name = e.path().filename().string();
    if (name.rfind(p.filename().string() + ".", 0) != 0) continue;
    std::ifstream in(e.path());
    for (std::string l; std::getline(in, l);) {
      std::smatch m;
      if (!std::regex_match(l, m, line)) continue;
      std::string call = m[1];
      if (call == "ioctl") {
        const std::string a = m[2];
        const auto comma = a.find(", ");
        call += " " + a.substr(comma + 2, a.find_first_of(",)", comma + 2) - comma - 2);
      }
      by_thread[name].push_back({call, std::stod(m[3])});
    }
  }
  TickCalls out;
  const std::vector<Call>* rt = nullptr;
  long most = 0;
  for (const auto& [tid, calls] : by_thread) {
    long sleeps = 0;
    for (const Call& c : calls) sleeps += c.name == "clock_nanosleep" ? 1 : 0;
    if (sleeps > most) {
      most = sleeps;
      rt = &calls;
    }
  }
  if (rt == nullptr) return out;
  long tick = -1;
  std::map<std::string, long> counts;
  std::vector<double> sff;
  for (const Call& c : *rt) {
    if (c.name == "clock_nanosleep") {
      ++tick;
      continue;
    }
    if (tick < skip || tick >= most - skip) continue;
    ++counts[c.name];
    if (c.name.find("EVIOCSFF") != std::string::npos) sff.push_back(c.seconds * 1e6);
  }
  long elsewhere = 0;
  for (const auto& [tid, calls] : by_thread) {
    if (&calls == rt) continue;
    for (const Call& c : calls) {
      if (c.name.find("EVIOCSFF") == std::string::npos) continue;
      ++elsewhere;
      sff.push_back(c.seconds * 1e6);
    }
  }
  if (most > 0) out.sff_elsewhere_per_tick = static_cast<double>(elsewhere) / most;
  out.ticks = most - 2 * skip;
  for (const auto& [name, n] : counts) out.per_tick[name] = static_cast<double>(n) / out.ticks;
  if (!sff.empty()) {
    std::sort(sff.begin(), sff.end());
    out.evioc_sff_us_median = sff[sff.size() / 2];
  }
  return out;
}

inline std::string describe(const TickCalls& t) {
  std::ostringstream os;
  os << t.ticks << " ticks:";
  for (const auto& [name, n] : t.per_tick) os << " " << name << " " << n;
  os << "; on other threads EVIOCSFF " << t.sff_elsewhere_per_tick << " a tick";
  os << "; EVIOCSFF median " << t.evioc_sff_us_median << " us";
  return os.str();
}

}  // namespace hapticd::reference
