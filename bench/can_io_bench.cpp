// The CAN driver's tick I/O cost with its simulated drive (BENCHMARKS.md, "CAN driver"): one
// read (drain: the TPDO or encoder answer, heartbeats, then the EAGAIN that ends the drain) and
// one write (CiA 402: RPDO and SYNC, hapticd's heartbeat every 20th tick; ODrive:
// Set_Input_Torque and the encoder request) through the driver over the socketpair, for each
// profile. The drive answers in the same thread between ticks (its thread is stopped after
// enable), so no thread hand-over is in the numbers. Driver-only time is measured around
// read+write alone; the full tick adds the simulated drive's own work.
#include <benchmark/benchmark.h>

#include "bench_support.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace {

using namespace hapticd;
using bench::counter;

void tick_bench(benchmark::State& state, const char* example, bool driver_only) {
  // The drive on the runner's thread answers at once unless the host holds that thread up: a
  // loaded host ran out of the examples' 100 ms SDO wait (as in tests/can/can_rig.h).
  const config::Config cfg = bench::load_example(example, {"device.can.sdo_timeout_ms=2000"});
  wiring::Loopback pair = wiring::find_driver("can").make_loopback(cfg);
  {
    sim::PeerRunner runner(*pair.peer);  // answers configure's and enable's requests
    pair.device->configure();
    pair.device->enable();
  }
  const Device& can = *pair.device;
  const std::uint64_t sent0 = counter(can, "frames_sent");
  const std::uint64_t received0 = counter(can, "frames_received");
  bench::run_ticks(state, *pair.device, *pair.peer, driver_only);
  const double ticks = static_cast<double>(state.iterations());
  const double sent = static_cast<double>(counter(can, "frames_sent") - sent0) / ticks;
  const double received = static_cast<double>(counter(can, "frames_received") - received0) / ticks;
  state.counters["frames_out"] = sent;
  state.counters["frames_in"] = received;
  // One send(2) per frame out; one recvmsg(2) per frame in plus the one that finds the socket
  // empty.
  state.counters["syscalls"] = sent + received + 1.0;
  pair.device->disable();
  pair.device->close();
}

void BM_CanCia402DriverTick(benchmark::State& state) { tick_bench(state, "can-cia402.yaml", true); }
void BM_CanCia402TickWithDrive(benchmark::State& state) {
  tick_bench(state, "can-cia402.yaml", false);
}
void BM_CanOdriveDriverTick(benchmark::State& state) { tick_bench(state, "can-odrive.yaml", true); }
void BM_CanOdriveTickWithAxis(benchmark::State& state) {
  tick_bench(state, "can-odrive.yaml", false);
}

BENCHMARK(BM_CanCia402DriverTick)->UseManualTime();
BENCHMARK(BM_CanCia402TickWithDrive);
BENCHMARK(BM_CanOdriveDriverTick)->UseManualTime();
BENCHMARK(BM_CanOdriveTickWithAxis);

}  // namespace

BENCHMARK_MAIN();
