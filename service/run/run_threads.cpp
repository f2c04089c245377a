#include "service/run/run_threads.h"

#include <pthread.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <system_error>

namespace hapticd::service {

RtThread::RtThread(loop::ServoLoop& loop, int priority, int cpu, bool realtime, loop::RtStatus& rt)
    : loop_(loop), ended_fd_(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
  if (ended_fd_ < 0) throw std::system_error(errno, std::system_category(), "eventfd");
  thread_ = std::thread([this, priority, cpu, realtime, &rt] {
    try {
      if (realtime) loop::configure_rt_thread(priority, cpu, rt);
    } catch (const std::exception& e) {
      error_ = e.what();  // only a CPU that does not exist; checked earlier too
    }
    ready_.store(true, std::memory_order_release);   // publishes rt and error_
    gate_.wait(kClosed, std::memory_order_acquire);  // until start() or a stop
    if (error_.empty() && gate_.load(std::memory_order_acquire) == kOpen) {
      result_ = loop_.run(stop_);
    }
    finished_.store(true, std::memory_order_release);
    const std::uint64_t one = 1;
    // Cannot fail short of a bad descriptor; the supervisor's poll time-out is the fallback.
    [[maybe_unused]] const ssize_t n = write(ended_fd_, &one, sizeof one);
  });
  // So `ps -L` and top show which thread is the loop (the others are named too).
  pthread_setname_np(thread_.native_handle(), "hapticd-rt");
}

void RtThread::open_gate(Gate to) noexcept {
  int closed = kClosed;
  gate_.compare_exchange_strong(closed, to, std::memory_order_acq_rel);
  gate_.notify_all();
}

void RtThread::start() noexcept {
  ticks_at_start_ = loop_.ticks_done();  // a re-armed loop counts on from its last run
  open_gate(kOpen);
}

void RtThread::wait_running() const {
  while (loop_.ticks_done() == ticks_at_start_ && !finished()) {
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
}

void RtThread::request_stop() noexcept {
  stop_.store(true);
  open_gate(kCancelled);  // no effect once started: the loop sees stop_ at its next tick
}

RtThread::~RtThread() {
  request_stop();
  if (thread_.joinable()) thread_.join();
  close(ended_fd_);
}

std::string RtThread::wait_ready() {
  while (!ready_.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return error_;
}

const loop::LoopResult& RtThread::join() {
  if (thread_.joinable()) thread_.join();
  return result_;
}

}  // namespace hapticd::service
