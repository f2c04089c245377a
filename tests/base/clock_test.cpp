// The one monotonic clock: it moves forward, agrees with CLOCK_MONOTONIC through std::chrono's
// steady_clock (both are CLOCK_MONOTONIC on Linux), and the absolute sleep does not return early.
#include <gtest/gtest.h>

#include <chrono>

#include "base/clock.h"

namespace hapticd::base {
namespace {

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

TEST(Clock, IsCLOCK_MONOTONICInNanosecondsAndMilliseconds) {
  const std::int64_t before = steady_ns();
  const std::int64_t ns = monotonic_ns();
  const std::int64_t ms = monotonic_ms();
  const std::int64_t after = steady_ns();
  EXPECT_LE(before, ns);
  EXPECT_LE(ns, after);
  EXPECT_GE(ms, ns / 1'000'000);
  EXPECT_LE(ms, after / 1'000'000);
}

TEST(Clock, TheAbsoluteSleepNeverWakesBeforeItsDeadline) {
  for (int i = 0; i < 20; ++i) {
    const std::int64_t deadline = monotonic_ns() + 200'000;  // 0.2 ms
    sleep_until_ns(deadline);
    EXPECT_GE(monotonic_ns(), deadline);
  }
  const std::int64_t past = monotonic_ns() - 1'000'000;
  sleep_until_ns(past);  // a deadline already gone returns at once
  EXPECT_GE(monotonic_ns(), past);
}

}  // namespace
}  // namespace hapticd::base
