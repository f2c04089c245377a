// The evdev driver's tick I/O cost with its simulated device (BENCHMARKS.md, "evdev driver"):
// one read (the events of the tick's frame, then the recv that finds the socket empty) and one
// write (the effect's update, EVIOCSFF's stand-in) through the driver over the loopback
// socketpair. The device answers in the same thread between ticks (its thread is stopped after
// enable), so no thread hand-over is in the numbers. Driver-only time is measured around
// read+write alone; the full tick adds the simulated device's own work (the plant step).
#include <benchmark/benchmark.h>

#include "bench_support.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace {

using namespace hapticd;

std::uint64_t counter(const Device& d, std::string_view name) {
  for (const base::Counter& c : d.counters()) {
    if (c.name() == name) return c.value();
  }
  return 0;
}

void tick_bench(benchmark::State& state, bool driver_only) {
  const config::Config cfg = bench::load_example("evdev.yaml");
  wiring::Loopback pair = wiring::find_driver("evdev").make_loopback(cfg);
  {
    sim::PeerRunner runner(*pair.peer);  // answers configure's and enable's requests
    pair.device->configure();
    pair.device->enable();
    runner.wait_idle();
  }
  const std::uint64_t frames = counter(*pair.device, "axis_events");
  const std::uint64_t updates = counter(*pair.device, "effect_updates");
  bench::run_ticks(state, *pair.device, *pair.peer, driver_only);
  const double ticks = static_cast<double>(state.iterations());
  const double in = static_cast<double>(counter(*pair.device, "axis_events") - frames) / ticks;
  const double out = static_cast<double>(counter(*pair.device, "effect_updates") - updates) / ticks;
  state.counters["frames_in"] = in;
  state.counters["updates_out"] = out;
  // Per frame in, three recv(2) (the update's answer, EV_ABS, SYN_REPORT) and the one that
  // finds the socket empty; one send(2) per update.
  state.counters["syscalls"] = 3.0 * in + 1.0 + out;
  pair.device->disable();
  pair.device->close();
}

void BM_EvdevDriverTick(benchmark::State& state) { tick_bench(state, true); }
void BM_EvdevTickWithDevice(benchmark::State& state) { tick_bench(state, false); }

BENCHMARK(BM_EvdevDriverTick)->UseManualTime();
BENCHMARK(BM_EvdevTickWithDevice);

}  // namespace

BENCHMARK_MAIN();
