// The threads of `hapticd run`: the RT thread that owns the servo loop, and the supervisor
// (the calling thread) that turns a stop signal into a stop request, feeds the systemd
// watchdog while ticks advance, and wakes the moment the loop ends.
#pragma once

#include <atomic>
#include <string>
#include <thread>

#include "drivers/device.h"
#include "loop/rt_setup.h"
#include "loop/servo_loop.h"
#include "service/stop_signals.h"

namespace hapticd::service {

class RtThread {
 public:
  // Starts the RT thread: it configures itself (SCHED_FIFO, CPU) when `realtime`, publishes
  // `rt`, runs the loop, then wakes the supervisor. Throws std::system_error when the wake-up
  // channel cannot be created.
  RtThread(loop::ServoLoop& loop, int priority, int cpu, bool realtime, loop::RtStatus& rt);
  // Requests a stop and joins: the loop never outlives its owner.
  ~RtThread();
  RtThread(const RtThread&) = delete;
  RtThread& operator=(const RtThread&) = delete;

  // Blocks until the RT thread has configured itself; returns why it could not ("" if it did).
  std::string wait_ready();
  // Supervises until the loop ends; returns what stopped it ("duration", "signal SIGTERM").
  std::string supervise(SignalWatch& signals);
  // After supervise(): what the loop did.
  const loop::LoopResult& result() const { return result_; }

 private:
  loop::ServoLoop& loop_;
  int ended_fd_ = -1;  // eventfd the RT thread writes once the loop has returned
  std::atomic<bool> stop_{false};
  std::atomic<bool> ready_{false};
  std::atomic<bool> finished_{false};
  std::string error_;
  loop::LoopResult result_;
  std::thread thread_;
};

}  // namespace hapticd::service
