// The coupling design's cost (BENCHMARKS.md): Naghshtabrizi and Hespanha's Example 1 with the
// felt weight, the whole search of `hapticd design-coupling` at order 3 and 5 (default
// budget), on CSDP and, when this build found libdsdp-dev, on DSDP: the measurement by which
// CSDP was chosen.
#include <benchmark/benchmark.h>

#include "analysis/coupling_design.h"
#include "analysis/sdp_backends.h"
#include "analysis/transparency_weight.h"
#include "analysis/wall_model.h"

namespace {

using namespace hapticd::analysis;

CouplingSpec example1(int order) {
  CouplingSpec s;
  s.environment = environment_filter({1000, 20, 0.02, WallDiscretization::kBackward});
  s.weight = felt_weight({{0.1, 0.03}, {100, -99}}, 1.0, 0.02);
  s.sample_period = 0.02;
  s.device_damping = 10;
  s.allowed_damping = 10;
  s.order = order;
  return s;
}

void run(benchmark::State& state, const SdpSolver& solver) {
  const CouplingSpec spec = example1(static_cast<int>(state.range(0)));
  CouplingDesign d;
  for (auto _ : state) d = design_coupling(spec, {}, solver);  // the command's default budget
  state.counters["gamma_felt"] = d.verdict.gamma;
  state.counters["sdp_solves"] = d.sdp_solves;
  state.counters["steps"] = d.steps;
}

void BM_DesignCouplingCsdp(benchmark::State& state) { run(state, *make_csdp_solver()); }
BENCHMARK(BM_DesignCouplingCsdp)->Arg(3)->Arg(5)->Unit(benchmark::kSecond)->Iterations(1);

#ifdef HAPTICD_BENCH_DSDP
void BM_DesignCouplingDsdp(benchmark::State& state) { run(state, *make_dsdp_solver()); }
BENCHMARK(BM_DesignCouplingDsdp)->Arg(3)->Arg(5)->Unit(benchmark::kSecond)->Iterations(1);
#endif

}  // namespace

BENCHMARK_MAIN();
