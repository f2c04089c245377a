// The thread a driver hands its output to when the device call blocks until the device has
// taken it (hid_write's synchronous transfer, EVIOCSFF to a device in user space): the RT
// thread never waits for the device, this thread does. It runs at SCHED_FIFO one below the
// loop, so it preempts everything but the loop and never the loop itself.
#pragma once

#include <functional>
#include <thread>

namespace hapticd::io {

// The SCHED_FIFO priority of an output thread: one below the loop's, at least 1.
int output_thread_priority(int loop_priority) noexcept;

// Not RT-safe. Starts `body` on a thread named `name` (at most 15 characters) at SCHED_FIFO
// `priority`. Best effort: without the privilege the thread runs as an ordinary one, which
// falls behind under load (each driver counts what that costs it).
std::thread start_output_thread(const char* name, int priority, std::function<void()> body);

}  // namespace hapticd::io
