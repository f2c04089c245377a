// Runs a loopback peer on its own thread, as a device runs on its own clock: whenever the
// driver has written something the peer handles it and answers. In freerun, where nothing
// may depend on timing, PacedDevice (paced_device.h) waits for the peer to be idle after every
// write, so a loopback run is as reproducible as the in-process sim.
#pragma once

#include <atomic>
#include <string>
#include <thread>

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

  // RT-safe (no allocation, lock or syscall but FIONREAD): returns once everything written to
  // the peer so far has been handled and answered, or the peer has failed.
  void wait_idle() const noexcept;
  // Not RT-safe, after stop(): why the peer failed ("" if it did not).
  std::string error() const;

 private:
  void run(int priority);

  LoopbackPeer& peer_;
  int stop_fd_ = -1;  // eventfd: wakes the thread to stop
  std::atomic<bool> busy_{false};
  std::atomic<bool> failed_{false};
  std::string error_;
  std::thread thread_;
};

}  // namespace hapticd::sim
