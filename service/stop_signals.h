// The process's signal policy. A signal must never end hapticd with output enabled, so every
// catchable signal whose default action would terminate (or stop) the process is blocked in
// main() before any thread exists - every thread inherits the mask - and taken synchronously
// through a signalfd by whoever supervises: a stop request, handled like SIGTERM. Signals
// whose only harm is their default action (SIGPIPE, SIGXFSZ, SIGTTIN, SIGTTOU) are ignored,
// so the write that provoked them fails with an error the caller reports (EPIPE, EFBIG).
// SIGKILL, SIGSTOP and a crash cannot be caught: for those the device side must fail safe
// (docs/devices.md says what each driver relies on).
//
// A thread that exists before main() (a sanitizer's runtime thread, a library's) does not
// have the mask, and the kernel may hand it a process-directed signal. So every stop signal
// also has a handler: wherever it runs, it writes the signal's number to a self-pipe that
// SignalWatch reads beside its signalfd.
#pragma once

#include <optional>
#include <span>
#include <string>

namespace hapticd::service {

// The signals that are taken through SignalWatch, never by their default action: SIGINT,
// SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGVTALRM, SIGPROF, SIGTRAP, SIGABRT,
// SIGXCPU, SIGIO, SIGPWR, SIGSTKFLT, SIGSYS, SIGTSTP (a stopped loop would hold its last force)
// and every real-time signal. Each is handled like SIGTERM, except SIGHUP in `hapticd run`,
// which reloads the configuration file (run_session.h).
std::span<const int> stop_signal_numbers();

// Not RT-safe. Call first in main(), before any thread: blocks the stop signals, gives them
// the self-pipe handler, and ignores SIGPIPE, SIGXFSZ, SIGTTIN and SIGTTOU.
void install_signal_policy();

// Not RT-safe. For sub-commands that never enable output (check, verify, export): the stop
// signals get their default actions back and are unblocked, so Ctrl-C ends them at once.
void release_stop_signals();

// Async-signal-safe. Hands a stop signal caught by another handler to the supervisor (the
// crash guard does this for a SIGABRT sent by another process, which is a stop, not a crash).
void forward_stop_signal(int sig) noexcept;

// "SIGTERM", "SIGRTMIN+3": the name a person recognises.
std::string signal_name(int sig);

// A signalfd over the stop signals, and the self-pipe their handler writes. Blocked signals
// stay pending until taken, so a stop requested at any moment - during start-up included - is
// seen by the next take_pending().
class SignalWatch {
 public:
  SignalWatch();  // throws std::system_error when the signalfd cannot be created
  ~SignalWatch();
  SignalWatch(const SignalWatch&) = delete;
  SignalWatch& operator=(const SignalWatch&) = delete;

  // Not RT-safe; never blocks. The next pending stop signal, or none.
  std::optional<int> take_pending() noexcept;
  // For poll(2): readable while a stop signal is pending.
  int fd() const noexcept { return fd_; }
  // For poll(2) too: readable when the handler caught one on a thread without the mask.
  int pipe_fd() const noexcept;

 private:
  int fd_ = -1;
};

}  // namespace hapticd::service
