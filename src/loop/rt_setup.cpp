#include "loop/rt_setup.h"

#include <time.h>

#include <malloc.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <fcntl.h>

#include <cerrno>
#include <cstdint>
#include <stdexcept>

#include "base/errno_text.h"

namespace hapticd::loop {

void lock_process_memory(RtStatus& status) {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    status.memory_locked = true;
    mallopt(M_TRIM_THRESHOLD, -1);  // never give heap back: a later sbrk would fault pages in
    mallopt(M_MMAP_MAX, 0);         // keep large blocks on the locked heap
  } else {
    status.warnings.push_back(std::string("mlockall failed (") + base::errno_text(errno) +
                              "): pages of the RT thread may fault; run as root or with "
                              "CAP_IPC_LOCK and LimitMEMLOCK=infinity");
  }
}

void keep_off_cpu(int cpu, RtStatus& status) {
  const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
  if (cpu < 0 || cpus < 2 || cpu >= cpus) return;
  cpu_set_t set;
  CPU_ZERO(&set);
  for (long c = 0; c < cpus; ++c)
    if (c != cpu) CPU_SET(static_cast<unsigned>(c), &set);
  const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
  if (rc == 0) {
    status.others_off_rt_cpu = true;
  } else {
    status.warnings.push_back("keeping the non-RT threads off CPU " + std::to_string(cpu) +
                              " failed (" + base::errno_text(rc) + ")");
  }
}

void configure_rt_thread(int priority, int cpu, RtStatus& status) {
  if (cpu >= 0) {
    const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    if (cpu >= cpus) {
      throw std::runtime_error("loop.cpu: CPU " + std::to_string(cpu) +
                               " does not exist (this machine has " + std::to_string(cpus) + ")");
    }
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(cpu), &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    if (rc == 0) {
      status.cpu = cpu;
    } else {
      status.warnings.push_back("pinning to CPU " + std::to_string(cpu) + " failed (" +
                                base::errno_text(rc) + ")");
    }
  }
  sched_param sp{};
  sp.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  if (rc == 0) {
    status.fifo = true;
    status.priority = priority;
  } else {
    status.warnings.push_back(std::string("SCHED_FIFO priority ") + std::to_string(priority) +
                              " refused (" + base::errno_text(rc) +
                              "): running SCHED_OTHER with 1 ns timer slack; wake latency will "
                              "suffer; run as root or with CAP_SYS_NICE and LimitRTPRIO");
  }
  if (!status.fifo) {
    // Under SCHED_OTHER the default 50 us timer slack would delay every wake-up.
    status.timer_slack_1ns = prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) == 0;
  }
}

CpuDmaLatencyRequest::CpuDmaLatencyRequest(RtStatus& status) {
  fd_ = open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  const std::int32_t zero = 0;
  if (fd_ >= 0 && write(fd_, &zero, sizeof zero) == static_cast<ssize_t>(sizeof zero)) {
    status.cpu_dma_latency_zero = true;
    return;
  }
  status.warnings.push_back(std::string("/dev/cpu_dma_latency: ") + base::errno_text(errno) +
                            ": CPUs may enter deep idle states and wake the loop late");
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
}

CpuDmaLatencyRequest::~CpuDmaLatencyRequest() {
  if (fd_ >= 0) close(fd_);  // closing the file withdraws the request
}

void prefault_stack(std::size_t bytes) noexcept {
  // Grow the stack by `bytes` right below the current frame and write every page of it, so
  // the deepest frames the ticks will use are already committed (and locked by mlockall).
  auto* p = static_cast<volatile unsigned char*>(__builtin_alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += 4096) p[i] = 0;
}

}  // namespace hapticd::loop
