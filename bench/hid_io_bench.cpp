// The HID driver's tick I/O cost with its simulated device (BENCHMARKS.md, "HID driver"): one
// read (the drain: every pending input report, then the recv that finds the socket empty) and
// one write (the force's output report; for pid, Set Constant Force) through the driver over
// the loopback socketpair, for each profile. The device answers in the same thread between
// ticks (its thread is stopped after enable), so no thread hand-over is in the numbers.
// Driver-only time is measured around read+write alone; the full tick adds the simulated
// device's own work (its codec and the plant step).
#include <benchmark/benchmark.h>

#include "bench_support.h"
#include "drivers/hid/hid_device.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace {

using namespace hapticd;

void tick_bench(benchmark::State& state, const char* example, bool driver_only) {
  const config::Config cfg = bench::load_example(example);
  wiring::Loopback pair = wiring::find_driver("hid").make_loopback(cfg);
  {
    sim::PeerRunner runner(*pair.peer);  // answers configure's feature reports and the enable
    pair.device->configure();
    pair.device->enable();
    runner.wait_idle();
  }
  pair.peer->service();  // the enable's answer, so the first tick has a sample
  auto& hid = dynamic_cast<drivers::hid::HidDevice&>(*pair.device);
  const drivers::hid::HidCounters before = hid.hid_counts();
  bench::run_ticks(state, *pair.device, *pair.peer, driver_only);
  const drivers::hid::HidCounters after = hid.hid_counts();
  const double ticks = static_cast<double>(state.iterations());
  const double in = static_cast<double>(after.input_reports + after.state_reports -
                                        before.input_reports - before.state_reports) /
                    ticks;
  const double out = static_cast<double>(after.output_reports - before.output_reports) / ticks;
  state.counters["reports_in"] = in;
  state.counters["reports_out"] = out;
  // One recv(2) per report in plus the one that finds the socket empty; one send(2) per
  // report out.
  state.counters["syscalls"] = in + 1.0 + out;
  pair.device->disable();
  pair.device->close();
}

void BM_HidReportDriverTick(benchmark::State& state) { tick_bench(state, "hid-report.yaml", true); }
void BM_HidReportTickWithDevice(benchmark::State& state) {
  tick_bench(state, "hid-report.yaml", false);
}
void BM_HidPidDriverTick(benchmark::State& state) { tick_bench(state, "hid-pid.yaml", true); }
void BM_HidPidTickWithDevice(benchmark::State& state) { tick_bench(state, "hid-pid.yaml", false); }
// Two axes (issue 37): one Set Constant Force per joint a tick.
void BM_HidPidXyDriverTick(benchmark::State& state) { tick_bench(state, "hid-pid-xy.yaml", true); }
void BM_HidPidXyTickWithDevice(benchmark::State& state) {
  tick_bench(state, "hid-pid-xy.yaml", false);
}

BENCHMARK(BM_HidReportDriverTick)->UseManualTime();
BENCHMARK(BM_HidReportTickWithDevice);
BENCHMARK(BM_HidPidDriverTick)->UseManualTime();
BENCHMARK(BM_HidPidTickWithDevice);
BENCHMARK(BM_HidPidXyDriverTick)->UseManualTime();
BENCHMARK(BM_HidPidXyTickWithDevice);

}  // namespace

BENCHMARK_MAIN();
