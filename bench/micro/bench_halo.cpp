// Halo exchange of a cell field (gather, and the reverse sum used by deposition) on an N^3 box,
// triply periodic so that a single rank also exchanges (with itself). Iterations are fixed so
// that every rank runs the same number; the time is the slowest rank's (manual time).
// Reported: bytes/s = bytes this rank packs and sends per second (all six faces).
#include <benchmark/benchmark.h>

#include "coloc/partition/field.hpp"
#include "coloc/partition/halo.hpp"

namespace {

void haloBench(benchmark::State& state, bool reverse) {
  const int n = static_cast<int>(state.range(0));
  const int ghost = static_cast<int>(state.range(1));
  coloc::GlobalGrid g;
  g.cells = {n, n, n};
  g.periodic = {true, true, true};
  const auto dec = coloc::Decomposition::uniform(coloc::Comm::world(), g);
  coloc::CellField f(coloc::cellLayout(dec, ghost), 1.0);
  coloc::HaloPlan plan(dec, f.layout());
  plan.gather(f);  // warm-up, allocates buffers
  long long bytes = 0;
  for (auto _ : state) {
    dec.comm().barrier();
    const double t0 = MPI_Wtime();
    if (reverse)
      plan.scatterSum(f, coloc::Fold::Keep);
    else
      plan.gather(f);
    const double dt = dec.comm().max(MPI_Wtime() - t0);
    state.SetIterationTime(dt);
    bytes += plan.bytesPerGather();
  }
  state.SetBytesProcessed(bytes);
  state.counters["ranks"] = dec.size();
  state.counters["bytes_per_exchange"] = static_cast<double>(plan.bytesPerGather());
}

void BM_HaloGather(benchmark::State& s) {
  haloBench(s, false);
}
void BM_HaloScatterSum(benchmark::State& s) {
  haloBench(s, true);
}

}  // namespace

BENCHMARK(BM_HaloGather)
    ->Args({32, 1})
    ->Args({128, 1})
    ->Args({128, 2})
    ->Iterations(30)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HaloScatterSum)
    ->Args({32, 1})
    ->Args({128, 1})
    ->Iterations(30)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
