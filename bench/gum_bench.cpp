// Monte Carlo (JCGM 101) of the location-error model: 1e6 trials (issue 6 target: < 1 s on
// this 2-core machine), and the GUF of the same model for scale.
#include <benchmark/benchmark.h>

#include "bench/location_mcm.hpp"

using namespace probeloop;

static void BM_McmLocationError(benchmark::State& state) {
  const auto p = bench::locationErrorProblem();
  uncertainty::McmOptions o;
  o.fixed_trials = state.range(0);
  for (auto _ : state) {
    const auto r = uncertainty::monteCarlo(p, bench::LocationErrorModel{}, o);
    benchmark::DoNotOptimize(r.u);
    state.counters["u_um_per_m"] = r.u;
    state.counters["interval_low"] = r.symmetric_low;
    state.counters["interval_high"] = r.symmetric_high;
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_McmLocationError)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_GufLocationError(benchmark::State& state) {
  const auto p = bench::locationErrorProblem();
  for (auto _ : state) {
    const auto r = uncertainty::propagate<32>(p, bench::LocationErrorModel{});
    benchmark::DoNotOptimize(r.u_c);
    state.counters["u_um_per_m"] = r.u_c;
  }
}
BENCHMARK(BM_GufLocationError)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
