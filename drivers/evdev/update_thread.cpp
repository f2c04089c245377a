#include "drivers/evdev/update_thread.h"

#include <algorithm>

#include "base/clock.h"
#include "drivers/io/output_thread.h"

namespace hapticd::drivers::evdev {
namespace {

constexpr std::uint64_t kPayloadMask = 0xFFFF'FFFF;
constexpr std::uint64_t kSeqMask = 0x7FFF'FFFF;  // 31 bits: bit 63 is kTaken

std::uint32_t seq_of(std::uint64_t slot) noexcept {
  return static_cast<std::uint32_t>((slot >> 32) & kSeqMask);
}
std::uint32_t payload_of(std::uint64_t slot) noexcept {
  return static_cast<std::uint32_t>(slot & kPayloadMask);
}
// Wrap-aware over the 31 bits: sequence number a is at or past b.
bool reached(std::uint32_t a, std::uint32_t b) noexcept {
  return static_cast<std::int32_t>((a - b) << 1) >= 0;
}
std::uint32_t packed(const wire::Effect& e) noexcept {
  return static_cast<std::uint16_t>(e.id) | (static_cast<std::uint32_t>(e.direction) << 16);
}
wire::Effect unpacked(std::uint32_t e) noexcept {
  wire::Effect effect;
  effect.id = static_cast<std::int16_t>(static_cast<std::uint16_t>(e & 0xFFFF));
  effect.direction = static_cast<std::uint16_t>(e >> 16);
  return effect;
}

}  // namespace

UpdateThread::UpdateThread(EvdevTransport& transport, int priority, Timing timing,
                           Counters counters)
    : transport_(transport), timing_(timing), c_(counters) {
  thread_ = io::start_output_thread("hapticd-evout", priority, [this] { run(); });
}

UpdateThread::~UpdateThread() {
  stop_.store(true, std::memory_order_seq_cst);
  bell_.fetch_add(1, std::memory_order_release);
  bell_.notify_one();
  thread_.join();
}

void UpdateThread::start_session(const Session& session) noexcept {
  effects_[0].store(packed(session.effects[0]), std::memory_order_release);
  effects_[1].store(packed(session.effects[1]), std::memory_order_release);
  mode_.store(session.mode, std::memory_order_release);
  error_.store(0, std::memory_order_release);
  late_.store(false, std::memory_order_release);
  late_ns_.store(0, std::memory_order_release);
  streak_.store(0, std::memory_order_release);
}

// RT-safe: called every tick.
bool UpdateThread::post(std::int16_t level, std::uint16_t second) noexcept {
  const std::uint64_t seq = (seq_of(slot_.load(std::memory_order_relaxed)) + 1) & kSeqMask;
  const std::uint64_t v =
      (seq << 32) | (std::uint64_t{second} << 16) | static_cast<std::uint16_t>(level);
  // seq_cst, with the load of asleep_ below and the thread's store of asleep_ before it looks
  // at the slot again: one of the two sees the other, so a level is never left unwoken.
  const std::uint64_t before = slot_.exchange(v, std::memory_order_seq_cst);
  if (asleep_.load(std::memory_order_seq_cst)) {
    bell_.fetch_add(1, std::memory_order_release);
    bell_.notify_one();
  }
  return (before & kTaken) == 0;
}

// RT-safe. The stop is asked for before level 0 is handed over, and the thread looks for a
// stop before it takes a level: the stop comes first.
bool UpdateThread::post_stop(std::uint16_t second) noexcept {
  stops_asked_.fetch_add(1, std::memory_order_seq_cst);
  return post(0, mode_.load(std::memory_order_acquire) == Mode::kDirected ? second : 0);
}

void UpdateThread::stop_effect() noexcept {
  const std::uint32_t asked = stops_asked_.load(std::memory_order_acquire);
  const int effects = mode_.load(std::memory_order_acquire) == Mode::kPerAxis ? 2 : 1;
  for (int k = 0; k < effects; ++k) {
    // best effort: a device that is gone says so to the reads
    transport_.write_ff(unpacked(effects_[k].load(std::memory_order_acquire)).id, 0);
  }
  stops_made_.store(asked, std::memory_order_release);
  done_.notify_all();
}

void UpdateThread::run() noexcept {
  while (!stop_.load(std::memory_order_acquire)) {
    if (stops_asked_.load(std::memory_order_acquire) !=
        stops_made_.load(std::memory_order_relaxed)) {
      stop_effect();
      continue;
    }
    std::uint64_t v = slot_.load(std::memory_order_acquire);
    if ((v & kTaken) != 0) {
      const std::uint32_t bell = bell_.load(std::memory_order_acquire);
      asleep_.store(true, std::memory_order_seq_cst);
      if ((slot_.load(std::memory_order_seq_cst) & kTaken) != 0 &&
          !stop_.load(std::memory_order_seq_cst)) {
        bell_.wait(bell, std::memory_order_acquire);
      }
      asleep_.store(false, std::memory_order_relaxed);
      continue;
    }
    // Fails when the RT thread handed a newer level over meanwhile: that one is taken next.
    if (!slot_.compare_exchange_weak(v, v | kTaken, std::memory_order_acq_rel)) continue;
    update(payload_of(v));
    done_.store(seq_of(v), std::memory_order_release);
    done_.notify_all();
  }
}

// One EVIOCSFF: false when the kernel refused it (its errno kept, the first of the session).
bool UpdateThread::update_one(wire::Effect effect) noexcept {
  const int error = transport_.update(effect);
  if (error == 0) {
    c_.taken.add();
    return true;
  }
  int none = 0;
  error_.compare_exchange_strong(none, error, std::memory_order_acq_rel);
  return false;
}

// The update posted, timed as one: kPerAxis makes both effects' EVIOCSFF, effects[0]'s first
// (the simulated device steps its plant at effects[1]'s, the end of the tick's update).
void UpdateThread::update(std::uint32_t payload) noexcept {
  const auto level = static_cast<std::int16_t>(static_cast<std::uint16_t>(payload & 0xFFFF));
  const auto second = static_cast<std::uint16_t>(payload >> 16);
  const Mode mode = mode_.load(std::memory_order_acquire);
  wire::Effect first = unpacked(effects_[0].load(std::memory_order_acquire));
  first.level = level;
  if (mode == Mode::kDirected) first.direction = second;
  const std::int64_t t0 = base::monotonic_ns();
  if (update_one(first) && mode == Mode::kPerAxis) {
    wire::Effect other = unpacked(effects_[1].load(std::memory_order_acquire));
    other.level = static_cast<std::int16_t>(second);
    update_one(other);
  }
  judge(base::monotonic_ns() - t0);
}

// The time an update took, against what the declared delay covers.
void UpdateThread::judge(std::int64_t ns) noexcept {
  if (ns > longest_ns_) {
    longest_ns_ = ns;
    c_.longest_us.set(static_cast<std::uint64_t>(ns / 1000));
  }
  if (ns <= timing_.covered_ns) {
    streak_.store(0, std::memory_order_relaxed);
    return;
  }
  c_.late.add();
  const int streak = streak_.load(std::memory_order_relaxed) + 1;
  streak_.store(streak, std::memory_order_relaxed);
  streak_longest_ns_ = streak == 1 ? ns : std::max(streak_longest_ns_, ns);
  if (streak >= timing_.late_fault && !late_.load(std::memory_order_acquire)) {
    late_ns_.store(streak_longest_ns_, std::memory_order_release);
    late_.store(true, std::memory_order_release);
  }
}

// Every level handed over has been through the transport, and every stop asked for made.
bool UpdateThread::idle() const noexcept {
  const std::uint64_t v = slot_.load(std::memory_order_acquire);
  return (v & kTaken) != 0 && reached(done_.load(std::memory_order_acquire), seq_of(v)) &&
         stops_made_.load(std::memory_order_acquire) ==
             stops_asked_.load(std::memory_order_acquire);
}

// RT-safe.
void UpdateThread::wait_done() const noexcept {
  while (!stop_.load(std::memory_order_acquire)) {
    const std::uint32_t done = done_.load(std::memory_order_acquire);
    if (idle()) return;
    done_.wait(done, std::memory_order_acquire);
  }
}

bool UpdateThread::flush(std::chrono::milliseconds timeout) const noexcept {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!idle()) {
    if (std::chrono::steady_clock::now() >= end) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

}  // namespace hapticd::drivers::evdev
