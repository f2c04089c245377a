// The one-slot mailbox through which a live reload hands the RT thread what it renders
// (docs/architecture.md: a swap at a tick boundary): a new control law for one joint
// (LawSwap), new walls for a scene of several (SceneSwap, scene_tick.h). The reload builds,
// checks and gates it off the RT thread (allocating as it likes), offer()s it, and the RT
// thread takes it at the start of its next tick without allocating, locking or waiting; what
// it replaced comes back through retire() for the offering side to destroy. A refused reload
// is noted here too, so the RT thread - the ring's only producer - can mark it in the tick log.
// T has `void continue_from(T& running) noexcept`: what carries over at the swap.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

#include "control/controller.h"

namespace hapticd::loop {

template <class T>
class TickSwap {
 public:
  // Not RT-safe (any one thread at a time). Hands `next` over; false when a previous offer has
  // not been taken yet, or the controller it replaced not retire()d yet (the caller keeps
  // ownership of `next` then).
  bool offer(T* next) noexcept {
    if (retired_.load(std::memory_order_acquire) != nullptr) return false;
    T* expected = nullptr;
    return pending_.compare_exchange_strong(expected, next, std::memory_order_acq_rel);
  }
  // Not RT-safe. The controller replaced by the last swap, once the RT thread is done with it
  // (ownership passes to the caller); null when there is none.
  T* retire() noexcept { return retired_.exchange(nullptr, std::memory_order_acq_rel); }
  // Not RT-safe. Takes an offer back that the RT thread has not taken (true: the caller owns
  // `offered` again); false when it was taken meanwhile.
  bool withdraw(T* offered) noexcept {
    return pending_.compare_exchange_strong(offered, nullptr, std::memory_order_acq_rel);
  }
  // Not RT-safe. A reload was refused: the RT thread writes a marker record at its next tick.
  void note_refused() noexcept { refused_.fetch_add(1, std::memory_order_release); }
  // Any thread: how many swaps the RT thread has made, and the tick the last one governs from.
  std::uint64_t swaps() const noexcept { return swaps_.load(std::memory_order_acquire); }
  std::uint64_t last_swap_tick() const noexcept {
    return swap_tick_.load(std::memory_order_acquire);
  }

  // RT-safe: called every tick. The offer, if any, already continued from `current` (a
  // controller's filter histories and delay line); `current` goes to retire(). The caller
  // switches to it from `tick` on. The continuation happens before the swap is published:
  // the offering side destroys `current` as soon as it sees the swap.
  T* take(T* current, std::uint64_t tick) noexcept {
    T* next = pending_.load(std::memory_order_acquire);
    if (next == nullptr) return nullptr;  // the usual tick: one load, nothing else
    // The slot for the retired one is free: the offering side takes it before offering again.
    // Claim the offer first: a concurrent withdraw() then fails and the offerer knows.
    if (!pending_.compare_exchange_strong(next, nullptr, std::memory_order_acq_rel)) {
      return nullptr;
    }
    next->continue_from(*current);
    retired_.store(current, std::memory_order_release);
    swap_tick_.store(tick, std::memory_order_release);
    swaps_.fetch_add(1, std::memory_order_acq_rel);
    return next;
  }
  // Not RT-safe. A loop is about to run and take offers (before its thread starts, so an
  // offer made once it runs never sees the previous loop's end).
  void loop_starting() noexcept { loop_ended_.store(false, std::memory_order_release); }
  // RT-safe: called once, as the loop returns. No offer is taken after it.
  void loop_ended() noexcept { loop_ended_.store(true, std::memory_order_release); }
  // Any thread. Whether no loop is running to take an offer.
  bool ended() const noexcept { return loop_ended_.load(std::memory_order_acquire); }

  // RT-safe: called every tick. Refusals noted since the last call.
  std::uint32_t take_refusals() noexcept {
    if (refused_.load(std::memory_order_acquire) == 0) return 0;
    return refused_.exchange(0, std::memory_order_acq_rel);
  }

 private:
  std::atomic<T*> pending_{nullptr};
  std::atomic<T*> retired_{nullptr};
  std::atomic<std::uint32_t> refused_{0};
  std::atomic<std::uint64_t> swaps_{0};
  std::atomic<std::uint64_t> swap_tick_{0};
  std::atomic<bool> loop_ended_{true};
};

// How an offer ended for the offering side (await_swap below).
enum class SwapOutcome {
  kTaken,      // the RT thread took it: last_swap_tick() is the tick it governs from
  kLoopEnded,  // the loop ended first; the offer is withdrawn (the caller owns it again)
  kTimedOut,   // the loop ran on but reached no tick boundary in time; withdrawn too
};

// Not RT-safe (sleeps). Waits until the offer of `offered` made when swaps() was `before` is
// taken, or the loop has ended, or `timeout` passes, then withdraws an offer not taken.
// A swap the RT thread makes while it is being withdrawn is reported as kTaken: the answer
// never disagrees with what the loop runs.
template <class T>
SwapOutcome await_swap(TickSwap<T>& swap, T* offered, std::uint64_t before,
                       std::chrono::milliseconds timeout) {
  // A deadline on the clock, not a count of sleeps: a starved control thread oversleeps, and
  // the time-out is about the RT thread, which may be starved too.
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (swap.swaps() == before && !swap.ended() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (!swap.withdraw(offered)) return SwapOutcome::kTaken;
  return swap.ended() ? SwapOutcome::kLoopEnded : SwapOutcome::kTimedOut;
}

// A new control law for a loop of one joint.
using LawSwap = TickSwap<control::Controller>;

}  // namespace hapticd::loop
