// The Falcon driver's tick I/O cost with the simulated Falcon (BENCHMARKS.md, "Falcon"): one
// read (the answer to the last packet, then the recv that finds the socket empty) and one write
// (the packet of three torques) through the driver over the loopback socketpair. The Falcon
// answers in the same thread between ticks (its thread is stopped after enable), so no thread
// hand-over is in the numbers. Driver-only time is measured around read+write alone; the full
// tick adds the simulated Falcon's work (its codec and the delta's step).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "bench_support.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace {

using namespace hapticd;
using bench::counter;

// The simulated Falcon takes any image of a plausible size as Novint's.
std::string image() {
  const std::string path = "/tmp/hapticd-bench-falcon-" + std::to_string(::getpid()) + ".bin";
  std::ofstream out(path, std::ios::binary);
  for (int i = 0; i < 7914; ++i) out.put(static_cast<char>(i));
  return path;
}

void tick_bench(benchmark::State& state, bool driver_only) {
  const std::string path = image();
  const config::Config cfg = bench::load_example("falcon.yaml", {"device.falcon.firmware=" + path});
  wiring::Loopback pair = wiring::find_driver("falcon").make_loopback(cfg);
  {
    sim::PeerRunner runner(*pair.peer);  // the load, homing and the enable's packet
    pair.device->configure();
    pair.device->enable();
    runner.wait_idle();
  }
  pair.peer->service();
  const std::uint64_t in0 = counter(*pair.device, "packets"),
                      out0 = counter(*pair.device, "packets_sent");
  bench::run_ticks(state, *pair.device, *pair.peer, driver_only, 0.05);  // N m on each arm
  const double ticks = static_cast<double>(state.iterations());
  state.counters["packets_in"] =
      static_cast<double>(counter(*pair.device, "packets") - in0) / ticks;
  state.counters["packets_out"] =
      static_cast<double>(counter(*pair.device, "packets_sent") - out0) / ticks;
  pair.device->disable();
  pair.device->close();
  ::unlink(path.c_str());
}

void BM_FalconDriverTick(benchmark::State& state) { tick_bench(state, true); }
void BM_FalconTickWithDevice(benchmark::State& state) { tick_bench(state, false); }

BENCHMARK(BM_FalconDriverTick)->UseManualTime();
BENCHMARK(BM_FalconTickWithDevice);

}  // namespace

BENCHMARK_MAIN();
