// The evdev driver's update thread. EVIOCSFF returns only once the device has taken the
// update, and a device in user space (uinput) answers each upload itself, as slowly as it
// likes: the RT thread must not wait for it. write() hands the effect's level over through one
// atomic word, the newest level wins (a level still waiting when the next comes is superseded,
// and counted), and this thread makes the update at SCHED_FIFO one below the loop
// (io::output_thread.h, as the HID driver's writer), timing each one against what the
// declared delay covers (covered_update_s, evdev_settings.h). The stop of the effect goes
// through this thread too: the kernel's evdev holds the node's mutex across EVIOCSFF
// (evdev_ioctl_handler) and an EV_FF write takes the same mutex (evdev_write), so a stop
// written beside an update in hand would wait for it, on whichever thread wrote it. Here it
// follows that update at once, ahead of any level still waiting, which level 0 replaces.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

#include "base/counters.h"
#include "drivers/evdev/evdev_transport.h"

namespace hapticd::drivers::evdev {

class UpdateThread {
 public:
  struct Counters {
    base::Counter& taken;       // updates the kernel took
    base::Counter& late;        // updates longer than the declared delay covers
    base::Counter& longest_us;  // the longest update, us
  };
  struct Timing {
    std::int64_t covered_ns = 0;  // an update longer than this is late
    int late_fault = 10;          // this many late updates in a row fault
  };
  // What one update is made of (docs/drivers/evdev.md, "Two axes"):
  //   kOne       one axis: effects[0] with the level posted
  //   kDirected  two axes, one effect: effects[0] with the level and the direction posted
  //   kPerAxis   two axes, an effect each: effects[0] and then effects[1], each with its level
  enum class Mode : std::uint8_t { kOne, kDirected, kPerAxis };
  struct Session {
    std::array<wire::Effect, 2> effects{};  // their ids and (kOne, kPerAxis) directions
    Mode mode = Mode::kOne;
  };
  // Not RT-safe. Starts the thread at SCHED_FIFO `priority`; `transport` must outlive it.
  UpdateThread(EvdevTransport& transport, int priority, Timing timing, Counters counters);
  // Stops the thread and joins it, after the update it has in hand.
  ~UpdateThread();
  UpdateThread(const UpdateThread&) = delete;
  UpdateThread& operator=(const UpdateThread&) = delete;

  // Not RT-safe; while idle (after flush). The effects later levels update (their ids and
  // directions), and a new session: the error and the late streak forgotten.
  void start_session(const Session& session) noexcept;

  // RT-safe: called every tick. Hands `level` (and `second`: kDirected the direction, kPerAxis
  // effects[1]'s level) on without waiting: one atomic exchange, and a futex wake only when the
  // thread is asleep (none while the device is busy with an update). True when it replaced an
  // update the thread had not taken: superseded.
  bool post(std::int16_t level, std::uint16_t second = 0) noexcept;
  // RT-safe: the stop of the effects (an EV_FF write of 0 each), then level 0 (kDirected: in
  // direction `second`): after the update in hand, ahead of any level waiting. Same as post()
  // otherwise.
  bool post_stop(std::uint16_t second = 0) noexcept;
  // RT-safe. The first update the device refused this session: its errno, or 0.
  int error() const noexcept { return error_.load(std::memory_order_acquire); }
  // RT-safe. Whether late_fault updates in a row were late this session.
  bool late() const noexcept { return late_.load(std::memory_order_acquire); }
  // Any thread. The longest update of the streak that set late(), ns.
  std::int64_t late_ns() const noexcept { return late_ns_.load(std::memory_order_acquire); }
  const Timing& timing() const noexcept { return timing_; }

  // RT-safe (a futex wait, no allocation). Returns once the newest level (and stop) posted has
  // been through the transport: a paced loopback (sim/peers/paced_device.h) then waits for
  // the simulated device alone.
  void wait_done() const noexcept;
  // Not RT-safe. Waits until every level posted has been through the transport, at most
  // `timeout`: true when it has.
  bool flush(std::chrono::milliseconds timeout) const noexcept;

 private:
  static constexpr std::uint64_t kTaken = std::uint64_t{1} << 63;
  void run() noexcept;
  bool idle() const noexcept;
  void stop_effect() noexcept;
  void update(std::uint32_t payload) noexcept;
  bool update_one(wire::Effect effect) noexcept;
  void judge(std::int64_t ns) noexcept;

  EvdevTransport& transport_;
  const Timing timing_;
  Counters c_;
  // The update handed over: bits 0-15 the level, 16-31 the second word (post), 32-62 its
  // sequence number, kTaken once the thread took it. The RT thread exchanges, the update thread
  // takes with a compare-exchange: an update is either taken or superseded, never both.
  std::atomic<std::uint64_t> slot_{kTaken};
  std::atomic<std::uint32_t> done_{0};  // the sequence number of the last level through
  std::atomic<std::uint32_t> bell_{0};  // the futex the thread sleeps on
  std::atomic<std::uint32_t> stops_asked_{0}, stops_made_{0};
  std::atomic<bool> asleep_{false}, stop_{false};
  // Each effect's id (low 16 bits) and direction (high 16), and the mode: set while idle.
  std::array<std::atomic<std::uint32_t>, 2> effects_{};
  std::atomic<Mode> mode_{Mode::kOne};
  std::atomic<int> error_{0};
  std::atomic<bool> late_{false};
  std::atomic<std::int64_t> late_ns_{0};
  std::atomic<int> streak_{0};
  std::int64_t streak_longest_ns_ = 0;
  std::int64_t longest_ns_ = 0;
  std::thread thread_;
};

}  // namespace hapticd::drivers::evdev
