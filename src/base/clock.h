// The monotonic clock every layer reads (the loop's schedule, drivers' time-outs and sample
// times, the peers' own clocks): one place, so that every time in a run is on CLOCK_MONOTONIC.
#pragma once

#include <cstdint>

namespace hapticd::base {

inline constexpr std::int64_t kNsPerS = 1'000'000'000;

// RT-safe. CLOCK_MONOTONIC in ns.
std::int64_t monotonic_ns() noexcept;
// RT-safe. CLOCK_MONOTONIC in ms (time-outs of the non-RT lifecycle calls).
std::int64_t monotonic_ms() noexcept;
// RT-safe: the loop's one blocking call besides the device read. Sleeps to an absolute
// CLOCK_MONOTONIC time; a signal interrupting the sleep does not move the deadline.
void sleep_until_ns(std::int64_t deadline_ns) noexcept;

}  // namespace hapticd::base
