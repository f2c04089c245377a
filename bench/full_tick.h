// The whole tick timed: the servo loop in freerun with the tick log ring, exactly the code of a
// realtime tick without the sleep. What the loop drives differs between benchmarks
// (tick_cost_bench.cpp: the sim device; scene_tick_bench.cpp: a delta and its walls); this
// times it the same way for each. Reports ns per tick, the loop's own compute-time percentiles
// (worst iteration) and heap allocations per tick.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

#include "alloc_counter.h"
#include "loop/servo_loop.h"

namespace hapticd::bench {

using TickRing = telemetry::SpscRing<telemetry::TickRecord>;

// Each iteration `make(ring, options)` builds, untimed, what one run needs and returns it
// owned (its `loop` member the ServoLoop, built on `options`, which run `ticks` ticks in
// freerun); the run is timed.
template <typename Make>
void run_full_ticks(benchmark::State& state, std::uint64_t ticks, loop::LoopOptions options,
                    Make make) {
  options.sample.realtime = false;
  options.max_ticks = ticks;
  TickRing ring(ticks + 1);
  std::vector<telemetry::TickRecord> drained(ticks + 1);
  std::uint64_t allocations = 0, total = 0;
  std::int64_t p50 = 0, p99 = 0, p999 = 0, max = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto rig = make(ring, options);
    const std::atomic<bool> stop{false};
    state.ResumeTiming();
    hapticd::testing::AllocationScope allocs;
    const auto r = rig->loop.run(stop);
    allocations += allocs.count();
    state.PauseTiming();
    total += r.ticks;
    ring.pop_many(drained.data(), drained.size());
    const auto& h = rig->loop.compute_time();
    p50 = std::max(p50, h.percentile_ns(0.5));
    p99 = std::max(p99, h.percentile_ns(0.99));
    p999 = std::max(p999, h.percentile_ns(0.999));
    max = std::max(max, h.max_ns());
    state.ResumeTiming();
  }
  state.counters["ns_per_tick"] = benchmark::Counter(
      static_cast<double>(total), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["allocs_per_tick"] =
      static_cast<double>(allocations) / static_cast<double>(std::max<std::uint64_t>(total, 1));
  // The loop's own per-tick compute time (read + step + write + clock reads), worst iteration.
  state.counters["compute_p50_ns"] = static_cast<double>(p50);
  state.counters["compute_p99_ns"] = static_cast<double>(p99);
  state.counters["compute_p999_ns"] = static_cast<double>(p999);
  state.counters["compute_max_ns"] = static_cast<double>(max);
}

}  // namespace hapticd::bench
