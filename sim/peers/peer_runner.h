// Runs a loopback peer on its own thread, as a device runs on its own clock: whenever the
// driver has written something the peer handles it and answers. PacedDevice (paced_device.h)
// waits for the peer to be idle after every write - in freerun, where nothing may depend on
// timing, and in a real-time `--loopback` run too: the peer shares the host with the loop, and
// on a kernel without full preemption (this machine's is PREEMPT_NONE) a thread woken at any
// SCHED_FIFO priority waits until whatever runs leaves the kernel - 30 ms was traced, on both
// cores at once, under a build. A simulated device held up by its host is not a device that
// failed; the loop waits for its answer, and a host stall shows as what it is, an overrun.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <thread>

#include "drivers/io/stop_event.h"
#include "sim/peers/loopback_peer.h"

namespace hapticd::sim {

class PeerRunner {
 public:
  // Not RT-safe. Starts the thread (none for a peer without a descriptor). `priority` > 0
  // asks for SCHED_FIFO at that priority (best effort: a device does not wait for the host).
  explicit PeerRunner(LoopbackPeer& peer, int priority = 0);
  // Stops and joins.
  ~PeerRunner() { stop(); }
  // Not RT-safe. Stops the thread and joins it. Idempotent.
  void stop() noexcept;
  PeerRunner(const PeerRunner&) = delete;
  PeerRunner& operator=(const PeerRunner&) = delete;

  // RT-safe (no allocation or lock; FIONREAD and a futex wait): returns once everything
  // written to the peer so far has been handled and answered, or the peer has failed. Sleeps
  // while it waits (never spins), so the peer runs even on the waiting thread's core below
  // its priority.
  void wait_idle() const noexcept;
  // Not RT-safe, after stop(): why the peer failed ("" if it did not).
  std::string error() const;

 private:
  void run(int priority);

  LoopbackPeer& peer_;
  std::optional<io::StopEvent> stop_;  // wakes the thread to stop
  std::atomic<bool> busy_{false};
  std::atomic<bool> failed_{false};
  std::atomic<std::uint32_t> rounds_{0};  // services done: what wait_idle sleeps on
  std::string error_;
  std::thread thread_;
};

}  // namespace hapticd::sim
