// Real-time set-up of the process and of the RT thread (docs/architecture.md): mlockall,
// SCHED_FIFO, CPU affinity, timer slack, stack prefault. Each step reports what it achieved so the
// daemon can say which guarantees were in force; nothing here fails silently.
#pragma once

#include <cstdint>

#include <string>
#include <vector>

namespace hapticd::loop {

struct RtStatus {
  bool memory_locked = false;  // mlockall(MCL_CURRENT | MCL_FUTURE) succeeded
  bool fifo = false;           // the RT thread runs SCHED_FIFO
  int priority = 0;
  int cpu = -1;  // CPU the RT thread is pinned to, -1 if not pinned
  bool timer_slack_1ns = false;
  bool cpu_dma_latency_zero = false;  // a 0 us PM QoS request holds CPUs out of deep idle
  bool others_off_rt_cpu = false;     // the non-RT threads are kept off the RT thread's CPU
  std::vector<std::string> warnings;  // one line per guarantee that is not in force, and why
};

// Not RT-safe; call once from main() before threads start. Locks memory and stops glibc from
// returning heap to the OS (so later frees cannot page-fault the RT thread).
void lock_process_memory(RtStatus& status);

// Not RT-safe; call from main() before starting any thread other than the RT thread, so
// every thread created afterwards inherits it: keeps the calling thread (and its later
// children) off `cpu`, leaving that CPU to the RT thread. On a kernel without full
// preemption a system call of a sibling thread on the RT CPU would delay its wake-up.
void keep_off_cpu(int cpu, RtStatus& status);

// Not RT-safe; call on the RT thread itself before its first tick. `cpu` < 0: no pinning.
// Throws std::runtime_error only for a CPU that does not exist (a configuration error).
void configure_rt_thread(int priority, int cpu, RtStatus& status);

// Holds a 0 us request on /dev/cpu_dma_latency for its lifetime, so no CPU enters an idle
// state whose exit latency would delay the RT thread's wake-up (what cyclictest does too).
// Not RT-safe; construct before the loop, destroy after it.
class CpuDmaLatencyRequest {
 public:
  explicit CpuDmaLatencyRequest(RtStatus& status);
  ~CpuDmaLatencyRequest();
  CpuDmaLatencyRequest(const CpuDmaLatencyRequest&) = delete;
  CpuDmaLatencyRequest& operator=(const CpuDmaLatencyRequest&) = delete;

 private:
  int fd_ = -1;
};

// Touches `bytes` of the calling thread's stack so the first ticks do not page-fault.
void prefault_stack(std::size_t bytes = 256 * 1024) noexcept;

}  // namespace hapticd::loop
