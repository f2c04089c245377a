// Cost of one tick: the controller alone (bare wall, wall behind a third-order coupling), the
// passivity observer alone (observing, damping), and the whole tick through the in-process sim
// device (read, step, write, log record push) as the servo loop runs it in freerun. Reports ns per
// tick, the loop's own compute-time percentiles, and heap allocations per tick (replaced operator
// new, see tests/support).
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <memory>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "control/passivity_observer.h"
#include "full_tick.h"
#include "loop/servo_loop.h"
#include "sim/sim_device.h"

namespace {

using hapticd::config::Config;
using hapticd::config::Override;

Config demo(std::vector<Override> sets = {}) {
  return hapticd::config::load_embedded_default(sets);
}

const std::vector<Override> kCoupled{
    {"wall.coupling.numerator", "[0.1, -0.0752, 0.0016, -0.0101]", "--set"},
    {"wall.coupling.denominator", "[1, -1.8407, 0.8444, -0.0037]", "--set"}};

// Positions sweeping in and out of a wall at 0 (contact about half the time).
std::array<double, 1024> positions() {
  std::array<double, 1024> x{};
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = 0.002 * std::sin(0.05 * static_cast<double>(i));
  return x;
}

void controller_step(benchmark::State& state, const Config& cfg) {
  hapticd::control::Controller ctl(hapticd::control::make_control_law(cfg));
  const auto x = positions();
  std::size_t i = 0;
  hapticd::testing::AllocationScope allocs;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ctl.step(x[i++ & 1023]));
  }
  state.counters["allocs_per_tick"] =
      benchmark::Counter(static_cast<double>(allocs.count()), benchmark::Counter::kAvgIterations);
}

void BM_ControllerStep_BareWall(benchmark::State& state) { controller_step(state, demo()); }
void BM_ControllerStep_ThirdOrderCoupling(benchmark::State& state) {
  controller_step(state, demo(kCoupled));
}

// The passivity observer alone, as the loop calls it every tick: observe the period just
// ended, let the controller add its damping, record the command. `range(0)`: 1 observe (b
// credited, the energy stays positive: no damping), 2 damp with b = 0 (the energy goes
// negative at once and the controller computes its damping on every tick that moves).
void BM_PassivityObserver(benchmark::State& state) {
  hapticd::control::ObserverParams p;
  p.mode = state.range(0) == 2 ? hapticd::config::PassivityControl::kDamp
                               : hapticd::config::PassivityControl::kObserve;
  p.device_damping = state.range(0) == 2 ? 0.0 : 2.0;
  p.sample_period = 1e-3;
  p.max_damping = 20.0;
  hapticd::control::PassivityObserver observer(p);
  hapticd::control::ControlLaw law;
  law.max_force = 10.0;
  const auto x = positions();
  std::size_t i = 0;
  hapticd::testing::AllocationScope allocs;
  for (auto _ : state) {
    const double xi = x[i++ & 1023];
    observer.observe(xi, true, 1);
    // Not const: Google Benchmark 1.8 on (Debian 13) deprecates DoNotOptimize of a const
    // struct, which the compiler may still optimise around.
    hapticd::control::Damping d = observer.damp(-2000.0 * std::max(xi, 0.0), law);
    observer.commanded(d.command, d.added);
    benchmark::DoNotOptimize(d);
  }
  state.counters["allocs_per_tick"] =
      benchmark::Counter(static_cast<double>(allocs.count()), benchmark::Counter::kAvgIterations);
  state.counters["damped_fraction"] = static_cast<double>(observer.damped_ticks()) /
                                      static_cast<double>(std::max<std::size_t>(i, 1));
}

// The servo loop in freerun over the sim device (bench/full_tick.h). Each iteration runs
// `range(0)` ticks; range(1): safety.passivity_controller 0 off, 1 observe (the default).
struct SimRig {
  SimRig(const Config& cfg, hapticd::bench::TickRing& ring, const hapticd::loop::LoopOptions& o)
      : device(cfg.device, cfg.loop.sample_period_s()),
        ctl(hapticd::control::make_control_law(cfg)),
        loop(device, ctl, &ring, o) {
    device.configure();
    device.enable();
  }
  hapticd::sim::SimDevice device;
  hapticd::control::Controller ctl;
  hapticd::loop::ServoLoop loop;
};

void BM_FullTick_SimDevice(benchmark::State& state) {
  const Config cfg = demo();
  hapticd::loop::LoopOptions lo;
  lo.observer = hapticd::control::observer_params(cfg, 0);
  lo.observer.mode = state.range(1) == 0 ? hapticd::config::PassivityControl::kOff
                                         : hapticd::config::PassivityControl::kObserve;
  hapticd::bench::run_full_ticks(
      state, static_cast<std::uint64_t>(state.range(0)), lo,
      [&](hapticd::bench::TickRing& ring, const hapticd::loop::LoopOptions& o) {
        return std::make_unique<SimRig>(cfg, ring, o);
      });
}

BENCHMARK(BM_ControllerStep_BareWall);
BENCHMARK(BM_ControllerStep_ThirdOrderCoupling);
BENCHMARK(BM_PassivityObserver)->Arg(1)->Arg(2)->ArgName("mode");
BENCHMARK(BM_FullTick_SimDevice)
    ->Args({100000, 0})
    ->Args({100000, 1})
    ->ArgNames({"ticks", "observer"})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
