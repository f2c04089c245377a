#include "reference/can/reference_runner.h"

#include <poll.h>
#include <pthread.h>
#include <sched.h>

namespace hapticd::reference {

ReferenceRunner::ReferenceRunner(ReferenceDevice& device, CanPort port, int priority)
    : device_(device), port_(std::move(port)) {
  log_.reserve(1 << 16);
  thread_ = std::thread([this, priority] { run(priority); });
}

void ReferenceRunner::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

std::vector<LoggedFrame> ReferenceRunner::log() const {
  std::lock_guard lock(log_mutex_);
  return log_;
}

void ReferenceRunner::run(int priority) {
  if (priority > 0) {
    sched_param sp{};
    sp.sched_priority = priority;
    pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  }
  std::vector<Frame> out;
  pollfd p{port_.fd(), POLLIN, 0};
  while (!stop_.load()) {
    poll(&p, 1, 1);
    out.clear();
    while (const auto f = port_.receive()) {
      const std::int64_t now = monotonic_ns();
      {
        std::lock_guard lock(log_mutex_);
        log_.push_back({*f, now, false});
      }
      device_.on_frame(*f, now, out);
    }
    const std::int64_t now = monotonic_ns();
    device_.on_clock(now, out);
    for (const Frame& f : out) {
      port_.send(f);
      std::lock_guard lock(log_mutex_);
      log_.push_back({f, now, true});
    }
  }
}

}  // namespace hapticd::reference
