// The RT thread of `hapticd run`: it owns the servo loop while it runs, and says when the loop
// has ended through a descriptor the supervisor (RunSession) polls.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "drivers/device.h"
#include "loop/rt_setup.h"
#include "loop/servo_loop.h"

namespace hapticd::service {

class RtThread {
 public:
  // Starts the RT thread: it configures itself (SCHED_FIFO, CPU) when `realtime`, publishes
  // `rt`, then waits at its start gate: the loop runs only once start() opens it, so all of
  // this happens before output is enabled. Throws std::system_error when the wake-up channel
  // cannot be created.
  RtThread(loop::ServoLoop& loop, int priority, int cpu, bool realtime, loop::RtStatus& rt);
  // Requests a stop (or closes the gate unopened) and joins: the loop never outlives its owner.
  ~RtThread();
  RtThread(const RtThread&) = delete;
  RtThread& operator=(const RtThread&) = delete;

  // Blocks until the RT thread has configured itself; returns why it could not ("" if it did).
  std::string wait_ready();
  // Opens the start gate: the loop's first tick follows at once (output is enabled by now).
  void start() noexcept;
  // After start(): blocks until the loop has made its first tick or ended (READY=1 means
  // servoing, not about to).
  void wait_running() const;
  // Any thread. Asks the loop to stop at its next tick; before start(), it never runs.
  void request_stop() noexcept;
  // Any thread. Whether the loop has ended (or will never run); readable (POLLIN) once it has.
  bool finished() const noexcept { return finished_.load(std::memory_order_acquire); }
  int ended_fd() const noexcept { return ended_fd_; }
  // Joins the thread (the loop must have ended or been asked to); then what the loop did.
  const loop::LoopResult& join();

 private:
  enum Gate : int { kClosed, kOpen, kCancelled };
  void open_gate(Gate to) noexcept;

  loop::ServoLoop& loop_;
  int ended_fd_ = -1;  // eventfd the RT thread writes once the loop has returned
  std::atomic<bool> stop_{false};
  std::atomic<bool> ready_{false};
  std::atomic<int> gate_{kClosed};
  std::uint64_t ticks_at_start_ = 0;  // the loop's ticks_done() when start() was called
  std::atomic<bool> finished_{false};
  std::string error_;
  loop::LoopResult result_;
  std::thread thread_;
};

}  // namespace hapticd::service
