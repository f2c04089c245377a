#include "tty_io.h"

#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "reference_clock.h"

namespace hapticd::reference {
namespace {

timespec until(std::int64_t deadline_ns) {
  const std::int64_t left = std::max<std::int64_t>(0, deadline_ns - now_ns());
  return timespec{static_cast<time_t>(left / 1'000'000'000),
                  static_cast<long>(left % 1'000'000'000)};
}

}  // namespace

TtyWaiter::TtyWaiter() : event_fd_(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
  if (event_fd_ < 0) throw std::runtime_error(std::string("eventfd: ") + std::strerror(errno));
}

TtyWaiter::~TtyWaiter() { ::close(event_fd_); }

void TtyWaiter::stop() {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(event_fd_, &one, sizeof one);
}

void TtyWaiter::re_arm() {
  std::uint64_t count = 0;
  [[maybe_unused]] const ssize_t n = ::read(event_fd_, &count, sizeof count);
}

TtyWaiter::Wake TtyWaiter::wait(int fd, bool listen, std::int64_t deadline_ns) {
  Wake w;
  pollfd p[2] = {{event_fd_, POLLIN, 0}, {fd, POLLIN, 0}};
  timespec t = until(deadline_ns);
  if (ppoll(p, listen ? 2 : 1, &t, nullptr) < 0 && errno != EINTR) return w;
  w.stop = (p[0].revents & POLLIN) != 0;
  if (!listen || w.stop) return w;
  w.lost = (p[1].revents & POLLNVAL) != 0;
  w.input = (p[1].revents & POLLIN) != 0;
  w.peer_absent = (p[1].revents & POLLHUP) != 0;
  if ((w.lost || w.peer_absent) && !w.input) {
    t = until(deadline_ns);  // the tty would wake us at once: sleep on stop() alone
    ppoll(p, 1, &t, nullptr);
    w.stop = (p[0].revents & POLLIN) != 0;
  }
  return w;
}

bool read_available(int fd, std::vector<std::uint8_t>& into) {
  std::uint8_t chunk[512];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n > 0) {
      into.insert(into.end(), chunk, chunk + n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    return !(n < 0 && errno == EBADF);
  }
}

bool write_frame(int fd, std::span<const std::uint8_t> frame) {
  std::size_t done = 0;
  const std::int64_t give_up = now_ns() + 2'000'000;
  while (done < frame.size()) {
    const ssize_t n = ::write(fd, frame.data() + done, frame.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN) return false;
    if (now_ns() >= give_up) return false;
    pollfd p{fd, POLLOUT, 0};
    const timespec t = until(give_up);
    ppoll(&p, 1, &t, nullptr);
  }
  return true;
}

void run_as_device(std::thread& thread) {
  sched_param p{};
  p.sched_priority = 70;
  (void)pthread_setschedparam(thread.native_handle(), SCHED_FIFO, &p);
}

}  // namespace hapticd::reference
