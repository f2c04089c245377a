// Runs a reference device on its own thread, as its firmware runs on its own processor: every
// frame from the bus handled when it arrives, its own timers serviced at least every
// millisecond, what it sends written to the bus. Everything it sent and received is logged
// with its time, for the tests to read afterwards.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "reference/can/can_wire.h"

namespace hapticd::reference {

class ReferenceDevice {
 public:
  virtual ~ReferenceDevice() = default;
  virtual void on_frame(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) = 0;
  virtual void on_clock(std::int64_t now_ns, std::vector<Frame>& out) = 0;
};

struct LoggedFrame {
  Frame frame;
  std::int64_t time_ns = 0;
  bool sent = false;  // by the device (else received from the bus)
};

class ReferenceRunner {
 public:
  // Starts the thread at `priority` (SCHED_FIFO when > 0 and allowed).
  ReferenceRunner(ReferenceDevice& device, CanPort port, int priority = 0);
  ~ReferenceRunner() { stop(); }
  void stop();
  // After stop() (or any time, copied under a lock).
  std::vector<LoggedFrame> log() const;

 private:
  void run(int priority);

  ReferenceDevice& device_;
  CanPort port_;
  std::atomic<bool> stop_{false};
  mutable std::mutex log_mutex_;
  std::vector<LoggedFrame> log_;
  std::thread thread_;
};

}  // namespace hapticd::reference
