// What a reference serial device's thread does with its tty: wait for input or for its next
// tick (or for stop()), read what came without blocking, and write a frame whole. It also
// reports whether anyone has the port open, as a USB CDC-ACM firmware sees the host's DTR: a
// pty master polls POLLHUP while its slave is closed (data written then would wait in the
// slave's buffer and reach the next opener stale; a real device's host side never sees what
// was sent while the port was closed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <thread>
#include <vector>

namespace hapticd::reference {

class TtyWaiter {
 public:
  TtyWaiter();  // throws std::runtime_error when no eventfd can be made
  ~TtyWaiter();
  TtyWaiter(const TtyWaiter&) = delete;
  TtyWaiter& operator=(const TtyWaiter&) = delete;

  struct Wake {
    bool stop = false;         // stop() was called
    bool input = false;        // the tty has bytes to read
    bool peer_absent = false;  // nobody has the other end open (POLLHUP)
    bool lost = false;         // the descriptor is gone (POLLNVAL): the test closed it
  };
  // Waits until input on `fd` (only when `listen`), stop(), or CLOCK_MONOTONIC `deadline_ns`.
  // A hung-up tty is not waited on (it would wake at once, forever): the rest of the time is
  // spent waiting for stop() alone.
  Wake wait(int fd, bool listen, std::int64_t deadline_ns);
  void stop();    // wakes wait() with `stop`, now and at every later call...
  void re_arm();  // ...until this is called (start() after stop()).

 private:
  int event_fd_ = -1;
};

// A device's firmware runs on its own processor, whatever the host is doing: its thread at
// SCHED_FIFO 70 (below hapticd's loop at 80), where the test may set it (root); as it is,
// where it may not. A device thread starved for 100 ms by a loaded test machine would move its
// mechanism without reporting it, which no real device does.
void run_as_device(std::thread& thread);

// Appends what `fd` holds to `into` without blocking. False when the descriptor is gone
// (EBADF); a hung-up pty master (EIO) or an empty one is just no input.
bool read_available(int fd, std::vector<std::uint8_t>& into);

// Writes `frame` whole to the non-blocking `fd`, waiting up to 2 ms for room. False when it
// could not: nothing of it, or (on a tty full to the brim) a torn head of it, went out.
bool write_frame(int fd, std::span<const std::uint8_t> frame);

}  // namespace hapticd::reference
