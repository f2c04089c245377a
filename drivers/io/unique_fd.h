// File-descriptor helpers shared by the transports: an owning descriptor, and the
// SOCK_SEQPACKET socketpair a driver and its loopback peer talk over (it keeps message
// boundaries, so one write is one report, one CAN frame, one edge batch). Not RT-safe except
// where marked.
#pragma once

#include <sys/types.h>
#include <unistd.h>

#include <cstddef>
#include <utility>

namespace hapticd::io {

// Owns one descriptor; closes it on destruction. Move-only.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) noexcept : fd_(fd) {}
  ~UniqueFd() { reset(); }
  UniqueFd(UniqueFd&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}
  UniqueFd& operator=(UniqueFd&& o) noexcept {
    if (this != &o) reset(std::exchange(o.fd_, -1));
    return *this;
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;

  // RT-safe.
  int get() const noexcept { return fd_; }
  explicit operator bool() const noexcept { return fd_ >= 0; }
  int release() noexcept { return std::exchange(fd_, -1); }
  void reset(int fd = -1) noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }

 private:
  int fd_ = -1;
};

// A connected pair of non-blocking, close-on-exec SOCK_SEQPACKET sockets. Throws
// std::system_error when the kernel refuses.
std::pair<UniqueFd, UniqueFd> seqpacket_pair();

// Sends `size` bytes on `socket` with `fd` passed along with the first of them (SCM_RIGHTS),
// never blocking or raising SIGPIPE (MSG_DONTWAIT | MSG_NOSIGNAL): sendmsg's result.
ssize_t send_with_fd(int socket, const void* data, std::size_t size, int fd) noexcept;

}  // namespace hapticd::io
