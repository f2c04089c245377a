#include "sim/peers/peer_runner.h"

#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/ioctl.h>

#include <cerrno>
#include <cstdint>

namespace hapticd::sim {
namespace {

bool has_unread(int fd) noexcept {
  int n = 0;
  return ioctl(fd, FIONREAD, &n) == 0 && n > 0;
}

}  // namespace

PeerRunner::PeerRunner(LoopbackPeer& peer, int priority) : peer_(peer) {
  if (peer_.fd() < 0) return;  // lives inside its driver: nothing to run
  stop_.emplace();
  thread_ = std::thread([this, priority] { run(priority); });
  pthread_setname_np(thread_.native_handle(), "hapticd-peer");
}

void PeerRunner::stop() noexcept {
  if (!thread_.joinable()) return;
  stop_->signal();
  thread_.join();
  stop_.reset();
}

void PeerRunner::run(int priority) {
  if (priority > 0) {
    sched_param sp{};
    sp.sched_priority = priority;
    pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);  // refused without privileges: fine
  }
  pollfd fds[2] = {{peer_.fd(), POLLIN, 0}, {stop_->fd(), POLLIN, 0}};
  while (true) {
    if (poll(fds, 2, peer_.service_interval_ms()) < 0 && errno != EINTR) break;
    // Asked to stop: what the driver said last (its disable) is still handled first, so the
    // simulated amplifier ends as the driver left it.
    const bool stopping = fds[1].revents != 0;
    if (stopping && (fds[0].revents & POLLIN) == 0) break;
    // busy before the first byte is taken, so wait_idle never sees "nothing unread, not busy"
    // while an answer is still being made.
    busy_.store(true);
    try {
      peer_.service();
    } catch (const std::exception& e) {
      error_ = e.what();
      failed_.store(true);
      busy_.store(false);
      rounds_.fetch_add(1);
      rounds_.notify_all();
      break;
    }
    busy_.store(false);
    rounds_.fetch_add(1);
    rounds_.notify_all();
    if (stopping || (fds[0].revents & (POLLHUP | POLLERR))) break;  // or the driver closed its end
  }
}

void PeerRunner::wait_idle() const noexcept {
  if (!thread_.joinable()) return;
  while (!failed_.load()) {
    const std::uint32_t round = rounds_.load();
    if (!has_unread(peer_.fd()) && !busy_.load() && !has_unread(peer_.fd())) return;
    // Asleep until the peer finishes a service round (a round that ended since `round` was
    // read returns at once), then judged again.
    rounds_.wait(round);
  }
}

std::string PeerRunner::error() const { return failed_.load() ? error_ : std::string(); }

}  // namespace hapticd::sim
