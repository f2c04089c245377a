// What every simulated device shares with the threads around it (docs/devices.md, "Loopback
// peers"): the faults a test told it to produce, and what the person holding it feels. Set and
// read from any thread without a lock; the device's own thread (a peer's service(), the sim
// device's read) acts on the faults and publishes the output.
#pragma once

#include <atomic>
#include <cstdint>
#include <initializer_list>

#include "sim/sim_axis.h"

namespace hapticd::sim {

// Faults of one enumeration (PeerFault, a transport's own: CanPeerFault, gpio::WireFault) that
// a device can be told to produce. Each is a flag: a lasting fault is read with active() (a
// device that stopped answering), a one-shot one with take() (the next frame of the wrong
// length).
template <typename Fault>
class FaultFlags {
 public:
  // `supported`: the faults this device can produce; inject() refuses the others.
  explicit FaultFlags(std::initializer_list<Fault> supported) noexcept {
    for (Fault f : supported) supported_ |= bit(f);
  }
  FaultFlags(const FaultFlags&) = delete;
  FaultFlags& operator=(const FaultFlags&) = delete;
  // Not while another thread injects: this device can produce `f` as well (what it can may
  // depend on its configuration: a fault line wired or not).
  void allow(Fault f) noexcept { supported_ |= bit(f); }

  // Any thread. Produce `f` from now on; false when this device cannot.
  bool inject(Fault f) noexcept {
    if ((supported_ & bit(f)) == 0) return false;
    set_.fetch_or(bit(f), std::memory_order_acq_rel);
    return true;
  }
  // Any thread. Whether `f` was injected (it stays so).
  bool active(Fault f) const noexcept {
    return (set_.load(std::memory_order_acquire) & bit(f)) != 0;
  }
  // The device's thread. Whether `f` was injected since the last take(). RT-safe: a load when
  // nothing was injected (the sim device's read takes one every tick).
  bool take(Fault f) noexcept {
    if (!active(f)) return false;
    return (set_.fetch_and(~bit(f), std::memory_order_acq_rel) & bit(f)) != 0;
  }

 private:
  static constexpr std::uint32_t bit(Fault f) noexcept { return 1u << static_cast<unsigned>(f); }
  std::uint32_t supported_ = 0;
  std::atomic<std::uint32_t> set_{0};
};

// The force the plant is given and whether the simulated amplifier is on
// (LoopbackPeer::applied_force, output_on), as the device's thread last published them.
class FeltOutput {
 public:
  // The device's thread.
  void publish(double force, bool on) noexcept {
    force_.store(force, std::memory_order_release);
    on_.store(on, std::memory_order_release);
    // After vanish() nothing drives the motor, whatever the device's thread was handling when
    // another thread made it vanish: checked again after the stores.
    if (gone_.load(std::memory_order_acquire)) zero();
  }
  void publish(const SimAxis& axis) noexcept { publish(axis.held_force(), axis.output_on()); }
  // Any thread. The device stopped driving at once (it faulted); whether its amplifier is on
  // stays the device thread's to publish.
  void drop_force() noexcept { force_.store(0.0, std::memory_order_release); }
  // Any thread. The device is gone (wires cut, unplugged): nothing is felt from now on.
  void vanish() noexcept {
    gone_.store(true, std::memory_order_release);
    zero();
  }

  // Any thread.
  double force() const noexcept { return force_.load(std::memory_order_acquire); }
  bool on() const noexcept { return on_.load(std::memory_order_acquire); }

 private:
  void zero() noexcept {
    force_.store(0.0, std::memory_order_release);
    on_.store(false, std::memory_order_release);
  }
  std::atomic<double> force_{0.0};
  std::atomic<bool> on_{false};
  std::atomic<bool> gone_{false};
};

}  // namespace hapticd::sim
