// A pseudo-terminal for a reference serial device: the device answers on the master end,
// hapticd opens the slave (/dev/pts/N) as it opens /dev/ttyACM0. The slave is made raw here,
// before anyone opens it, so nothing the device writes first is echoed back to it or has its
// CR turned into NL by the line discipline: the termios of a pty stay with the pair while the
// master is open, across the slave's closes and re-opens. set_raw() does the same for the
// gadget end of a USB CDC-ACM gadget (/dev/ttyGS0) in the kernel test machine.
#pragma once

#include <string>

namespace hapticd::reference {

struct PtyPair {
  int master = -1;         // O_RDWR | O_NOCTTY | O_NONBLOCK; closed by the destructor
  std::string slave_path;  // "/dev/pts/N"

  PtyPair() = default;
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;
  PtyPair(PtyPair&& o) noexcept;
  PtyPair& operator=(PtyPair&& o) noexcept;
  ~PtyPair();

  // Closes the master now: the slave's reader sees a hang-up, as on a USB unplug. Stop the
  // device running on it first.
  void close_master();
};

// Throws std::runtime_error when the system has no pty to give.
PtyPair open_pty_pair();

// cfmakeraw on `fd`'s tty (throws std::runtime_error when it is no tty).
void set_raw(int fd);

}  // namespace hapticd::reference
