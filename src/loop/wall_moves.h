// The mailbox through which a client's wall moves reach the RT thread (docs/operations.md,
// scene requests: move): each wall's newest place, written by the control thread and taken at
// the next tick boundary, with no gate in between (the gate proved the walls movable:
// gate/workspace_gate.h) and no lock. One sequence lock per wall: the offering side writes a
// place between two increments of its wall's counter; the RT thread takes a place only when it
// read the same even counter before and after it (a place torn by a concurrent offer is taken
// on the next tick). Every field is an atomic, so the lock is data-race free as written.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "config/config.h"
#include "kinematics/pose.h"

namespace hapticd::loop {

class WallMoves {
 public:
  // When the RT thread took the offers up to some number (any thread, after await).
  struct Taken {
    std::uint64_t tick = 0;    // the first tick that rendered them
    std::int64_t time_ns = 0;  // CLOCK_MONOTONIC when that tick took them
  };

  // Not RT-safe; one offering thread at a time. Wall `wall` (< config::kMaxWalls) goes to
  // `place` (m, finite). Returns the offer's number (1, 2, ...), for await().
  std::uint64_t offer(std::size_t wall, const kinematics::Vec3& place) noexcept;

  // RT-safe: called every tick. Calls move(wall, place) for each wall offered a new place since
  // the last take (its newest place), records `tick` and the time as when they were taken,
  // and returns how many walls moved. One atomic load when nothing was offered.
  template <class Move>
  std::size_t take(std::uint64_t tick, Move&& move) noexcept;

  // Not RT-safe (sleeps). Waits until offer `number` is taken or no loop runs (none) or
  // `timeout` passes (none).
  std::optional<Taken> await(std::uint64_t number, std::chrono::milliseconds timeout) const;

  // Not RT-safe: before the loop's thread starts. RT-safe: as the loop returns.
  void loop_starting() noexcept { loop_ended_.store(false, std::memory_order_release); }
  void loop_ended() noexcept { loop_ended_.store(true, std::memory_order_release); }

 private:
  struct Slot {
    std::atomic<std::uint64_t> sequence{0};  // odd while a place is being written
    std::array<std::atomic<double>, 3> place{};
    std::uint64_t taken = 0;  // RT thread only: the sequence of the place it took last
  };
  // RT-safe. Slot i's place when it holds one not taken yet; false when torn or already taken.
  bool read(Slot& s, kinematics::Vec3& place, bool& torn) noexcept;
  // RT-safe. Publishes what take() took.
  void taken(std::uint64_t offers, std::uint64_t tick) noexcept;

  std::array<Slot, config::kMaxWalls> slots_{};
  std::atomic<std::uint64_t> offered_{0};
  std::atomic<std::uint64_t> taken_{0};
  std::atomic<std::uint64_t> taken_tick_{0};
  std::atomic<std::int64_t> taken_ns_{0};
  std::atomic<bool> loop_ended_{true};
};

template <class Move>
std::size_t WallMoves::take(std::uint64_t tick, Move&& move) noexcept {
  const std::uint64_t offered = offered_.load(std::memory_order_acquire);
  if (offered == taken_.load(std::memory_order_relaxed)) return 0;  // the usual tick
  std::size_t moved = 0;
  bool torn = false;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    kinematics::Vec3 place;
    if (!read(slots_[i], place, torn)) continue;
    move(i, place);
    ++moved;
  }
  if (!torn) taken(offered, tick);  // otherwise the rest on the next tick
  return moved;
}

}  // namespace hapticd::loop
