#include "loop/law_swap.h"

#include <thread>

namespace hapticd::loop {

SwapOutcome await_swap(LawSwap& swap, control::Controller* offered, std::uint64_t before,
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

}  // namespace hapticd::loop
