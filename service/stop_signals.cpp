#include "service/stop_signals.h"

#include <fcntl.h>
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

// The self-pipe of the handler: written on whatever thread a stop signal lands, read by the
// supervisor. Created once, before any thread.
int g_pipe[2] = {-1, -1};

void on_stop_signal(int sig) {
  const int saved = errno;  // a handler must leave errno as it found it
  const auto byte = static_cast<unsigned char>(sig);
  [[maybe_unused]] const ssize_t n = write(g_pipe[1], &byte, 1);
  errno = saved;
}

sigset_t stop_set() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : all_stop_signals()) sigaddset(&set, sig);
  return set;
}

}  // namespace

std::span<const int> stop_signal_numbers() { return all_stop_signals(); }

void forward_stop_signal(int sig) noexcept { on_stop_signal(sig); }

// The handlers before the mask: once a stop signal shows as blocked (/proc/PID/status), one
// that the kernel hands to a thread older than main() (a sanitizer's) runs the handler, never
// the default action. Blocking first left a moment when it killed the process: seen once
// under ASan in a Debian 12 check (CliSignals.AStopDuringStartUpNeverEnablesOutput).
void install_signal_policy() {
  const sigset_t set = stop_set();
  if (g_pipe[0] < 0 && pipe2(g_pipe, O_NONBLOCK | O_CLOEXEC) == 0) {
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sa.sa_mask = set;  // one at a time
    sa.sa_flags = SA_RESTART;
    for (int sig : all_stop_signals()) sigaction(sig, &sa, nullptr);
  }
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  for (int sig : {SIGPIPE, SIGXFSZ, SIGTTIN, SIGTTOU}) signal(sig, SIG_IGN);
}

void release_stop_signals() {
  for (int sig : all_stop_signals()) signal(sig, SIG_DFL);
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

int SignalWatch::pipe_fd() const noexcept { return g_pipe[0]; }

std::optional<int> SignalWatch::take_pending() noexcept {
  signalfd_siginfo info{};
  for (;;) {
    const ssize_t n = read(fd_, &info, sizeof info);
    if (n == static_cast<ssize_t>(sizeof info)) return static_cast<int>(info.ssi_signo);
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN: nothing pending there
  }
  unsigned char byte = 0;
  if (g_pipe[0] >= 0 && read(g_pipe[0], &byte, 1) == 1) return static_cast<int>(byte);
  return std::nullopt;
}

}  // namespace hapticd::service
