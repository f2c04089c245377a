#include "service/stop_signals.h"

#include <signal.h>
#include <string.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <system_error>
#include <vector>

namespace hapticd::service {
namespace {

constexpr std::array kFixedStopSignals{SIGINT,  SIGTERM,   SIGHUP,    SIGQUIT, SIGUSR1, SIGUSR2,
                                       SIGALRM, SIGVTALRM, SIGPROF,   SIGTRAP, SIGABRT, SIGXCPU,
                                       SIGIO,   SIGPWR,    SIGSTKFLT, SIGSYS,  SIGTSTP};

// The real-time signals' numbers are only known at run time (glibc reserves a few).
const std::vector<int>& all_stop_signals() {
  static const std::vector<int> signals = [] {
    std::vector<int> s(kFixedStopSignals.begin(), kFixedStopSignals.end());
    for (int sig = SIGRTMIN; sig <= SIGRTMAX; ++sig) s.push_back(sig);
    return s;
  }();
  return signals;
}

sigset_t stop_set() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : all_stop_signals()) sigaddset(&set, sig);
  return set;
}

}  // namespace

std::span<const int> stop_signal_numbers() { return all_stop_signals(); }

void install_signal_policy() {
  const sigset_t set = stop_set();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  for (int sig : {SIGPIPE, SIGXFSZ, SIGTTIN, SIGTTOU}) signal(sig, SIG_IGN);
}

void release_stop_signals() {
  const sigset_t set = stop_set();
  pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
}

std::string signal_name(int sig) {
  if (sig >= SIGRTMIN && sig <= SIGRTMAX) {
    return sig == SIGRTMIN ? "SIGRTMIN" : "SIGRTMIN+" + std::to_string(sig - SIGRTMIN);
  }
  const char* abbrev = sigabbrev_np(sig);
  return abbrev != nullptr ? std::string("SIG") + abbrev : "signal " + std::to_string(sig);
}

SignalWatch::SignalWatch() {
  const sigset_t set = stop_set();
  fd_ = signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
  if (fd_ < 0) throw std::system_error(errno, std::system_category(), "signalfd");
}

SignalWatch::~SignalWatch() {
  if (fd_ >= 0) close(fd_);
}

std::optional<int> SignalWatch::take_pending() noexcept {
  signalfd_siginfo info{};
  for (;;) {
    const ssize_t n = read(fd_, &info, sizeof info);
    if (n == static_cast<ssize_t>(sizeof info)) return static_cast<int>(info.ssi_signo);
    if (n < 0 && errno == EINTR) continue;
    return std::nullopt;  // EAGAIN: nothing pending
  }
}

}  // namespace hapticd::service
