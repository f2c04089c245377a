// The loop's options for a test: `ticks` ticks back to back, no clock, no real-time set-up.
#pragma once

#include <cstdint>

#include "loop/servo_loop.h"

namespace hapticd::loop {

inline LoopOptions freerun(std::uint64_t ticks = 100) {
  LoopOptions o;
  o.sample.realtime = false;
  o.max_ticks = ticks;
  return o;
}

}  // namespace hapticd::loop
