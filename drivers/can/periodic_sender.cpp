#include "drivers/can/periodic_sender.h"

#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <cerrno>

#include "base/clock.h"

namespace hapticd::drivers::can {

void PeriodicSender::start(int fd, std::vector<Entry> entries, int priority) {
  if (thread_.joinable()) return;
  stop_.emplace();
  first_written_.store(0);
  thread_ = std::thread(
      [this, fd, e = std::move(entries), priority]() mutable { run(fd, std::move(e), priority); });
  pthread_setname_np(thread_.native_handle(), "hapticd-cankeep");
}

void PeriodicSender::stop() noexcept {
  if (!thread_.joinable()) return;
  stop_->signal();
  thread_.join();
  stop_.reset();
}

void PeriodicSender::wait_written(std::uint64_t n) const noexcept {
  while (thread_.joinable() && first_written_.load() < n) {
    pollfd p{stop_->fd(), POLLIN, 0};
    if (poll(&p, 1, 1) > 0) return;  // stopping
  }
}

void PeriodicSender::run(int fd, std::vector<Entry> entries, int priority) noexcept {
  if (priority > 0) {
    sched_param sp{};
    sp.sched_priority = priority;
    pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  }
  std::vector<std::int64_t> due;
  const std::int64_t start = base::monotonic_ns();
  for (const Entry& e : entries) due.push_back(e.first_ns == 0 ? start : e.first_ns);
  pollfd p{stop_->fd(), POLLIN, 0};
  while (!entries.empty()) {
    const std::int64_t next = *std::min_element(due.begin(), due.end());
    const std::int64_t wait = std::max<std::int64_t>(0, next - base::monotonic_ns());
    const timespec ts{static_cast<time_t>(wait / 1'000'000'000),
                      static_cast<long>(wait % 1'000'000'000)};
    const int r = ppoll(&p, 1, &ts, nullptr);
    if (r > 0) return;  // stop() was called
    if (r < 0 && errno != EINTR) return;
    const std::int64_t now = base::monotonic_ns();
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (now < due[i]) continue;
      const WireFrame w = CanSocket::to_wire(entries[i].frame);
      CanSocket::write_wire(fd, {&w, 1});
      if (i == 0) first_written_.fetch_add(1);
      // On the schedule, not from now (one frame per period), but never two within half a
      // period after a late one.
      due[i] = std::max(due[i] + entries[i].period_ns, now + entries[i].period_ns / 2);
    }
  }
}

}  // namespace hapticd::drivers::can
