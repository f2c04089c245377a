// The coupling design's cost (BENCHMARKS.md): Naghshtabrizi and Hespanha's Example 1 with the
// felt weight, the whole search of `hapticd design-coupling` at orders 3, 4 and 5 (default
// budget: the paper's cone complementarity stage, then the pole search), on CSDP and, when
// this build found libdsdp-dev, on DSDP: the measurement by which CSDP was chosen.
#include <benchmark/benchmark.h>

#include "analysis/coupling_design.h"
#include "analysis/sdp_backends.h"
#include "coupling_example1.h"

namespace {

using namespace hapticd::analysis;

void run(benchmark::State& state, const SdpSolver& solver) {
  const CouplingSpec spec = hapticd::testing::coupling_example1(static_cast<int>(state.range(0)));
  CouplingDesign d;
  for (auto _ : state) d = design_coupling(spec, {}, solver);  // the command's default budget
  state.counters["gamma_felt"] = d.verdict.gamma;
  state.counters["gamma_seed"] = d.gamma_seed;  // the cone complementarity stage's
  state.counters["sdp_solves"] = d.sdp_solves;
  state.counters["steps"] = d.steps;
}

void BM_DesignCouplingCsdp(benchmark::State& state) { run(state, *make_csdp_solver()); }
BENCHMARK(BM_DesignCouplingCsdp)->Arg(3)->Arg(4)->Arg(5)->Unit(benchmark::kSecond)->Iterations(1);

#ifdef HAPTICD_BENCH_DSDP
void BM_DesignCouplingDsdp(benchmark::State& state) { run(state, *make_dsdp_solver()); }
BENCHMARK(BM_DesignCouplingDsdp)->Arg(3)->Arg(4)->Arg(5)->Unit(benchmark::kSecond)->Iterations(1);
#endif

}  // namespace

BENCHMARK_MAIN();
