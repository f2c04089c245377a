#include "loop/wall_moves.h"

#include <thread>

#include "base/clock.h"

namespace hapticd::loop {

std::uint64_t WallMoves::offer(std::size_t wall, const kinematics::Vec3& place) noexcept {
  Slot& s = slots_[wall];
  const std::uint64_t was = s.sequence.load(std::memory_order_relaxed);
  s.sequence.store(was + 1, std::memory_order_relaxed);
  // Each coordinate a release (no fence: ThreadSanitizer does not follow fences): a reader that
  // sees one sees the odd sequence before it.
  for (int a = 0; a < 3; ++a) s.place[a].store(place[a], std::memory_order_release);
  s.sequence.store(was + 2, std::memory_order_release);
  return offered_.fetch_add(1, std::memory_order_acq_rel) + 1;
}

bool WallMoves::read(Slot& s, kinematics::Vec3& place, bool& torn) noexcept {
  const std::uint64_t before = s.sequence.load(std::memory_order_acquire);
  if (before == s.taken) return false;
  // Each an acquire: the second read of the sequence comes after them.
  for (int a = 0; a < 3; ++a) place[a] = s.place[a].load(std::memory_order_acquire);
  const std::uint64_t after = s.sequence.load(std::memory_order_relaxed);
  if ((before & 1u) != 0 || before != after) {
    torn = true;
    return false;
  }
  s.taken = before;
  return true;
}

void WallMoves::taken(std::uint64_t offers, std::uint64_t tick) noexcept {
  taken_tick_.store(tick, std::memory_order_relaxed);
  taken_ns_.store(base::monotonic_ns(), std::memory_order_relaxed);
  taken_.store(offers, std::memory_order_release);
}

std::optional<WallMoves::Taken> WallMoves::await(std::uint64_t number,
                                                 std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  // A tick is a millisecond or less: a tenth of it between looks answers within a tenth.
  while (taken_.load(std::memory_order_acquire) < number) {
    if (loop_ended_.load(std::memory_order_acquire) ||
        std::chrono::steady_clock::now() >= deadline) {
      return std::nullopt;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  // A later take may have stored its tick already: the answer is then that later tick's, which
  // also rendered this place (a newer one only for a wall offered again meanwhile).
  return Taken{taken_tick_.load(std::memory_order_relaxed),
               taken_ns_.load(std::memory_order_relaxed)};
}

}  // namespace hapticd::loop
