#include "drivers/io/unique_fd.h"

#include <sys/socket.h>

#include <cerrno>
#include <cstring>
#include <system_error>

namespace hapticd::io {

std::pair<UniqueFd, UniqueFd> seqpacket_pair() {
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds) != 0) {
    throw std::system_error(errno, std::system_category(), "socketpair(SOCK_SEQPACKET)");
  }
  return {UniqueFd(fds[0]), UniqueFd(fds[1])};
}

ssize_t send_with_fd(int socket, const void* data, std::size_t size, int fd) noexcept {
  iovec io{const_cast<void*>(data), size};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
  msghdr msg{};
  msg.msg_iov = &io;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  cmsghdr* c = CMSG_FIRSTHDR(&msg);
  c->cmsg_level = SOL_SOCKET;
  c->cmsg_type = SCM_RIGHTS;
  c->cmsg_len = CMSG_LEN(sizeof(int));
  std::memcpy(CMSG_DATA(c), &fd, sizeof fd);
  return ::sendmsg(socket, &msg, MSG_DONTWAIT | MSG_NOSIGNAL);
}

}  // namespace hapticd::io
