#include "pty_pair.h"

#include <fcntl.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace hapticd::reference {
namespace {

[[noreturn]] void fail(const std::string& what, int error) {
  throw std::runtime_error("pty: " + what + ": " + std::strerror(error));
}

}  // namespace

PtyPair::PtyPair(PtyPair&& o) noexcept
    : master(std::exchange(o.master, -1)), slave_path(std::move(o.slave_path)) {}

PtyPair& PtyPair::operator=(PtyPair&& o) noexcept {
  if (this != &o) {
    close_master();
    master = std::exchange(o.master, -1);
    slave_path = std::move(o.slave_path);
  }
  return *this;
}

PtyPair::~PtyPair() { close_master(); }

void PtyPair::close_master() {
  if (master >= 0) ::close(master);
  master = -1;
}

void set_raw(int fd) {
  termios t{};
  if (tcgetattr(fd, &t) != 0) fail("tcgetattr", errno);
  cfmakeraw(&t);
  if (tcsetattr(fd, TCSANOW, &t) != 0) fail("tcsetattr", errno);
}

PtyPair open_pty_pair() {
  PtyPair p;
  p.master = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (p.master < 0) fail("posix_openpt", errno);
  // Not inherited by the hapticd the test starts: a copy of the master there would keep the
  // slave from hanging up when the test closes its own (an unplug).
  if (fcntl(p.master, F_SETFD, FD_CLOEXEC) != 0) fail("FD_CLOEXEC", errno);
  if (grantpt(p.master) != 0) fail("grantpt", errno);
  if (unlockpt(p.master) != 0) fail("unlockpt", errno);
  char name[128];
  if (const int e = ptsname_r(p.master, name, sizeof name); e != 0) fail("ptsname_r", e);
  p.slave_path = name;
  // The slave's termios, set once through the slave itself: they outlive this open.
  const int slave = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (slave < 0) fail(std::string("open ") + name, errno);
  try {
    set_raw(slave);
  } catch (...) {
    ::close(slave);
    throw;
  }
  ::close(slave);
  return p;
}

}  // namespace hapticd::reference
