#include "loop/law_swap.h"

#include <thread>

namespace hapticd::loop {

SwapOutcome await_swap(LawSwap& swap, control::Controller* offered, std::uint64_t before,
                       std::chrono::milliseconds timeout) {
  // A deadline on the clock, not a count of sleeps: a starved control thread oversleeps, and
  // the time-out is about the RT thread, which may be starved too.
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  bool ended = false;
  while (swap.swaps() == before) {
    if (swap.ended()) {
      ended = true;
      break;
    }
    if (std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (!swap.withdraw(offered)) return SwapOutcome::kTaken;
  return ended ? SwapOutcome::kLoopEnded : SwapOutcome::kTimedOut;
}

}  // namespace hapticd::loop
