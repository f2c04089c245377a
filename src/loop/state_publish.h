// What the loop tells its clients each tick (client/state_layout.h, docs/clients.md): the
// tick's record as a state sample, with each joint's and the task's velocity by backward
// difference and the task force that acted, published into the state block.
#pragma once

#include <cstdint>

#include "client/state_layout.h"
#include "kinematics/pose.h"
#include "telemetry/state_block.h"
#include "telemetry/tick_record.h"

namespace hapticd::loop {

class StatePublisher {
 public:
  // Not RT-safe to build. `block` null: nothing is published.
  StatePublisher(telemetry::StateBlock* block, std::int64_t period_ns) noexcept
      : block_(block), rate_hz_(1e9 / static_cast<double>(period_ns)) {}

  // RT-safe: called every tick, with the tick's record as logged, the sample periods since the
  // previous tick, when the tick woke, and the task force that acted (zero after a fault).
  void publish(const telemetry::TickRecord& rec, std::uint32_t periods, std::int64_t wake_ns,
               const kinematics::Vec3& force) noexcept;
  // RT-safe. A new run: no previous position to difference.
  void restart() noexcept { previous_ = false; }

 private:
  telemetry::StateBlock* block_;
  double rate_hz_;  // 1 / T: the differences are divided by the periods between ticks
  bool previous_ = false;
  client::StateSample last_{};
};

}  // namespace hapticd::loop
