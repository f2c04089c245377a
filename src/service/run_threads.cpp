#include "service/run_threads.h"

#include <signal.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <chrono>

namespace hapticd::service {
namespace {

// SIGUSR1 is how the RT thread says "the loop has ended" to a supervisor in sigtimedwait.
constexpr int kLoopEnded = SIGUSR1;

sigset_t run_signals() {
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGINT);
  sigaddset(&s, SIGTERM);
  sigaddset(&s, kLoopEnded);
  return s;
}

}  // namespace

void block_run_signals() {
  const sigset_t s = run_signals();
  pthread_sigmask(SIG_BLOCK, &s, nullptr);
  // A tick log reaching a file-size limit must fail its write (counted, reported), not kill
  // the process with the motor enabled.
  signal(SIGXFSZ, SIG_IGN);
}

RtThread::RtThread(loop::ServoLoop& loop, int priority, int cpu, bool realtime, loop::RtStatus& rt)
    : loop_(loop), supervisor_(pthread_self()) {
  thread_ = std::thread([this, priority, cpu, realtime, &rt] {
    try {
      if (realtime) loop::configure_rt_thread(priority, cpu, rt);
    } catch (const std::exception& e) {
      error_ = e.what();  // only a CPU that does not exist; checked earlier too
    }
    ready_.store(true, std::memory_order_release);  // publishes rt and error_
    if (error_.empty()) result_ = loop_.run(stop_);
    finished_.store(true, std::memory_order_release);
    pthread_kill(supervisor_, kLoopEnded);
  });
}

RtThread::~RtThread() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

std::string RtThread::wait_ready() {
  while (!ready_.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return error_;
}

std::string RtThread::supervise() {
  std::string reason = "duration";
  const sigset_t sigs = run_signals();
  std::uint64_t watchdog_usec = 0;
  const bool watchdog = sd_watchdog_enabled(0, &watchdog_usec) > 0;
  std::uint64_t last_ticks = 0;
  while (!finished_.load(std::memory_order_acquire)) {
    const timespec wait{0, 50'000'000};
    const int sig = sigtimedwait(&sigs, nullptr, &wait);
    if ((sig == SIGINT || sig == SIGTERM) && !stop_.load()) {
      reason = sig == SIGINT ? "signal SIGINT" : "signal SIGTERM";
      spdlog::info("{} received: stopping", sig == SIGINT ? "SIGINT" : "SIGTERM");
      sd_notify(0, "STOPPING=1");
      stop_.store(true);
    }
    const std::uint64_t ticks = loop_.ticks_done();
    if (watchdog && ticks != last_ticks) sd_notify(0, "WATCHDOG=1");
    last_ticks = ticks;
  }
  thread_.join();  // result_ is complete
  return reason;
}

}  // namespace hapticd::service
