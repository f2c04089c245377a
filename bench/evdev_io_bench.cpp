// The evdev driver's tick I/O cost with its simulated device (BENCHMARKS.md, "evdev driver").
// The loop thread's part of a tick: one read (the events of the tick's frame, then the recv that
// finds the socket empty) and one write (the level handed to the update thread: one atomic
// exchange and, that thread being asleep since the last update, one futex wake). The whole tick
// adds what runs on the other threads, as a paced loopback runs it: the update thread's EVIOCSFF
// stand-in (the update sent, its answer awaited on its own socket) and the simulated device's
// step and answer on its thread (Device::wait_output, PeerRunner::wait_idle), thread hand-overs
// included.
#include <benchmark/benchmark.h>

#include <chrono>

#include "bench_support.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace {

using namespace hapticd;
using bench::counter;
using Clock = std::chrono::steady_clock;

void tick_bench(benchmark::State& state, bool loop_thread_only) {
  const config::Config cfg = bench::load_example("evdev.yaml");
  wiring::Loopback pair = wiring::find_driver("evdev").make_loopback(cfg);
  sim::PeerRunner runner(*pair.peer);
  Device& device = *pair.device;
  device.configure();
  device.enable();
  runner.wait_idle();
  const std::uint64_t frames = counter(device, "axis_events");
  const std::uint64_t updates = counter(device, "effect_updates");
  PositionSample s;
  double force = 0.5;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    benchmark::DoNotOptimize(device.read(s));
    benchmark::DoNotOptimize(device.write(force));
    const auto t1 = Clock::now();
    device.wait_output();
    runner.wait_idle();
    const auto t2 = Clock::now();
    force = -force;
    state.SetIterationTime(
        std::chrono::duration<double>((loop_thread_only ? t1 : t2) - t0).count());
  }
  const double ticks = static_cast<double>(state.iterations());
  const double in = static_cast<double>(counter(device, "axis_events") - frames) / ticks;
  const double out = static_cast<double>(counter(device, "effect_updates") - updates) / ticks;
  state.counters["frames_in"] = in;
  state.counters["updates_out"] = out;
  // On the loop's thread, per frame in two recv(2) (EV_ABS, SYN_REPORT), the one that finds the
  // socket empty, and one futex wake per update (the update thread sleeps between them here).
  state.counters["loop_syscalls"] = 2.0 * in + 1.0 + out;
  device.disable();
  device.close();
}

void BM_EvdevDriverTick(benchmark::State& state) { tick_bench(state, true); }
void BM_EvdevTickWithDevice(benchmark::State& state) { tick_bench(state, false); }

BENCHMARK(BM_EvdevDriverTick)->UseManualTime();
BENCHMARK(BM_EvdevTickWithDevice)->UseManualTime();

}  // namespace

BENCHMARK_MAIN();
