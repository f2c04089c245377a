#include "drivers/io/output_thread.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>

namespace hapticd::io {

int output_thread_priority(int loop_priority) noexcept { return std::max(1, loop_priority - 1); }

std::thread start_output_thread(const char* name, int priority, std::function<void()> body) {
  std::thread t(std::move(body));
  pthread_setname_np(t.native_handle(), name);
  sched_param sp{};
  sp.sched_priority = priority;
  // Refused without privileges: the thread then competes as an ordinary one.
  pthread_setschedparam(t.native_handle(), SCHED_FIFO, &sp);
  return t;
}

}  // namespace hapticd::io
