#include "drivers/io/unique_fd.h"

#include <sys/socket.h>

#include <cerrno>
#include <system_error>

namespace hapticd::io {

std::pair<UniqueFd, UniqueFd> seqpacket_pair() {
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds) != 0) {
    throw std::system_error(errno, std::system_category(), "socketpair(SOCK_SEQPACKET)");
  }
  return {UniqueFd(fds[0]), UniqueFd(fds[1])};
}

}  // namespace hapticd::io
