#include "service/run/crash_guard.h"

#include "service/stop_signals.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>

namespace hapticd::service {
namespace {

std::atomic<Device*> g_device{nullptr};

void on_crash(int sig, siginfo_t* info, void*) {
  // A SIGABRT sent by another process (kill -ABRT) is a request to stop, handled like
  // SIGTERM; abort() in this process is a crash.
  if (sig == SIGABRT && info != nullptr && info->si_pid != getpid()) {
    forward_stop_signal(sig);
    return;
  }
  // Async-signal-safe: an atomic load and write(2)s (or ioctl(2)s) of prebuilt messages.
  if (Device* d = g_device.exchange(nullptr)) d->emergency_stop();
  signal(sig, SIG_DFL);
  sigset_t only;
  sigemptyset(&only);
  sigaddset(&only, sig);
  pthread_sigmask(SIG_UNBLOCK, &only, nullptr);  // SIGABRT is blocked for the stop policy
  raise(sig);  // the default action: the core dump and exit status stay true
}

void install_once() noexcept {
  static const bool installed = [] {
    struct sigaction sa {};
    sa.sa_sigaction = on_crash;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_SIGINFO;
    for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) sigaction(sig, &sa, nullptr);
    return true;
  }();
  (void)installed;
}

}  // namespace

void guard_device_on_crash(Device* device) noexcept {
  install_once();
  g_device.store(device);
}

}  // namespace hapticd::service
