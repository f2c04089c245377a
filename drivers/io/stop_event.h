// How a thread that waits in poll(2) on its own descriptors is told to stop: an eventfd it
// polls beside them, signalled once. The threads drivers and peers run beside the loop use it
// (a CAN drive's keeper, drivers/can/periodic_sender.h; a loopback peer's runner,
// sim/peers/peer_runner.h).
#pragma once

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <system_error>

#include "drivers/io/unique_fd.h"

namespace hapticd::io {

class StopEvent {
 public:
  // Not RT-safe. Throws std::system_error when the kernel refuses an eventfd.
  StopEvent() : fd_(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
    if (!fd_) throw std::system_error(errno, std::system_category(), "eventfd");
  }
  // For poll(2): readable once signalled.
  int fd() const noexcept { return fd_.get(); }
  // Any thread, never fails: the waiting thread wakes and sees it.
  void signal() const noexcept {
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(fd_.get(), &one, sizeof one);
  }

 private:
  UniqueFd fd_;
};

}  // namespace hapticd::io
