// The serial driver's tick I/O cost with its simulated device (BENCHMARKS.md, "serial
// driver"): one read (what has arrived: the device's frame, then the read that finds the
// socket empty) and one write (the force's frame) through the driver over the loopback
// socketpair, for each example. The device answers in the same thread between ticks (its
// thread is stopped after enable), so no thread hand-over is in the numbers. Driver-only time
// is measured around read+write alone; the full tick adds the simulated device's work (its
// codec and the plant step: the pantograph's two joints through its kinematics).
#include <benchmark/benchmark.h>

#include <array>
#include <chrono>
#include <span>

#include "bench_support.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace {

using namespace hapticd;
using bench::counter;

void tick_bench(benchmark::State& state, const char* example, bool driver_only) {
  const config::Config cfg = bench::load_example(example);
  wiring::Loopback pair = wiring::find_driver("serial").make_loopback(cfg);
  {
    sim::PeerRunner runner(*pair.peer);  // answers configure's first frame and the enable's
    pair.device->configure();
    pair.device->enable();
    runner.wait_idle();
  }
  pair.peer->service();  // the enable's answer, so the first tick has a sample
  const std::uint64_t in0 = counter(*pair.device, "frames"),
                      out0 = counter(*pair.device, "frames_sent");
  // +-0.05 N (m) on each joint: within the pantograph's 0.12 N m.
  bench::run_ticks(state, *pair.device, *pair.peer, driver_only, 0.05);
  const double ticks = static_cast<double>(state.iterations());
  const double in = static_cast<double>(counter(*pair.device, "frames") - in0) / ticks;
  const double out = static_cast<double>(counter(*pair.device, "frames_sent") - out0) / ticks;
  state.counters["frames_in"] = in;
  state.counters["frames_out"] = out;
  // Over the socketpair: one read(2) per frame in plus the one that finds it empty, one
  // write(2) per frame out. On a tty: one read (a short one took everything) and one write.
  state.counters["syscalls"] = in + 1.0 + out;
  pair.device->disable();
  pair.device->close();
}

void BM_SerialHaplyDriverTick(benchmark::State& state) {
  tick_bench(state, "serial-haply-2diy.yaml", true);
}
void BM_SerialHaplyTickWithDevice(benchmark::State& state) {
  tick_bench(state, "serial-haply-2diy.yaml", false);
}
void BM_SerialStreamDriverTick(benchmark::State& state) {
  tick_bench(state, "serial-stream.yaml", true);
}
void BM_SerialStreamTickWithDevice(benchmark::State& state) {
  tick_bench(state, "serial-stream.yaml", false);
}

BENCHMARK(BM_SerialHaplyDriverTick)->UseManualTime();
BENCHMARK(BM_SerialHaplyTickWithDevice);
BENCHMARK(BM_SerialStreamDriverTick)->UseManualTime();
BENCHMARK(BM_SerialStreamTickWithDevice);

}  // namespace

BENCHMARK_MAIN();
