// The daemon's side of the state block (client/state_layout.h, docs/clients.md): a sealed
// memfd the loop writes every tick and clients map read-only, its descriptor passed over the
// control socket. Built and prefaulted before the loop; publish() is a few stores.
#pragma once

#include <cstdint>

#include "client/state_layout.h"

namespace hapticd::telemetry {

class StateBlock {
 public:
  // Not RT-safe. A block of `slots` (a power of two) samples; throws std::runtime_error naming
  // the system call that failed, std::invalid_argument for slots that are no power of two.
  StateBlock(std::uint32_t slots, std::int64_t sample_period_ns, std::uint32_t joints,
             std::uint32_t axes);
  ~StateBlock();
  StateBlock(const StateBlock&) = delete;
  StateBlock& operator=(const StateBlock&) = delete;

  // The descriptor to pass to a client (sealed: it cannot be grown, shrunk or mapped writable).
  int fd() const noexcept { return fd_; }
  std::uint32_t slots() const noexcept { return header_->slots; }

  // RT-safe: called every tick. Sample `s` into the next slot, under its sequence lock, then
  // counted in the header's head.
  void publish(const client::StateSample& s) noexcept;
  std::uint64_t published() const noexcept { return header_->head.load(std::memory_order_relaxed); }

 private:
  int fd_ = -1;
  void* map_ = nullptr;
  std::size_t bytes_ = 0;
  client::StateHeader* header_ = nullptr;
  client::StateSlot* slots_ = nullptr;
};

}  // namespace hapticd::telemetry
