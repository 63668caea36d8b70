// Coupling kernels: stencil computation, deposition (particles -> cells), interpolation
// (cells -> particles) and the drag laws, for 1e5 particles spread at random over a 64^3 block
// (one rank; the kernels are rank-local by construction, the halo sums are in bench_halo).
// Reported: items/s = particles processed per second.
//   build/bench/bench_coupling [--benchmark_filter=Deposit]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>
#include <vector>

#include "coloc/coupling/drag.hpp"
#include "coloc/coupling/kernel.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace {

using namespace coloc;
using namespace coloc::coupling;

constexpr int kCells = 64;

struct Setup {
  Decomposition dec;
  FieldLayout layout;
  std::vector<double> x, y, z, q;
  explicit Setup(std::size_t n)
      : dec(Decomposition::uniform(Comm(MPI_COMM_SELF), grid())), layout(cellLayout(dec, 1)) {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    x.resize(n), y.resize(n), z.resize(n), q.resize(n);
    for (std::size_t p = 0; p < n; ++p) {
      x[p] = u(rng), y[p] = u(rng), z[p] = u(rng), q[p] = u(rng);
    }
  }
  static GlobalGrid grid() {
    GlobalGrid g;
    g.length = {1, 1, 1};
    g.cells = {kCells, kCells, kCells};
    return g;
  }
};

KernelKind kindOf(const benchmark::State& s) {
  return s.range(1) ? KernelKind::Trilinear : KernelKind::Centroid;
}

void BM_StencilCompute(benchmark::State& state) {
  Setup s(static_cast<std::size_t>(state.range(0)));
  Stencils st;
  for (auto _ : state) {
    benchmark::DoNotOptimize(st.compute(kindOf(state), s.dec, s.layout, s.x, s.y, s.z, s.x.size()));
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_Deposit(benchmark::State& state) {
  Setup s(static_cast<std::size_t>(state.range(0)));
  Stencils st;
  st.compute(kindOf(state), s.dec, s.layout, s.x, s.y, s.z, s.x.size());
  CellField f(s.layout, 0.0);
  for (auto _ : state) {
    deposit(st, s.q, 1.0, f);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_Interpolate(benchmark::State& state) {
  Setup s(static_cast<std::size_t>(state.range(0)));
  Stencils st;
  st.compute(kindOf(state), s.dec, s.layout, s.x, s.y, s.z, s.x.size());
  CellField f(s.layout, 1.0);
  std::vector<double> out(s.x.size());
  for (auto _ : state) {
    interpolate(st, f, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

// The sampling and deposit of a coupling step (7 fields sampled, 5 deposited) with the
// particles in cell order, as the DEM's bin sort leaves them: range(2) = 0 one pass a field (the
// one-field kernels), 1 one fused pass (kernel.hpp).
struct StepSetup : Setup {
  Stencils st;
  std::vector<CellField> f;
  std::vector<std::vector<double>> out;
  explicit StepSetup(std::size_t n) : Setup(n), f(7, CellField(layout, 1.0)) {
    // Cell order: sort by the cell of the centre (z, y, x), as the DEM's bins do.
    std::vector<std::size_t> idx(n);
    for (std::size_t p = 0; p < n; ++p) idx[p] = p;
    auto cell = [&](std::size_t p) {
      auto c = [](double v) { return static_cast<long>(v * kCells); };
      return (c(z[p]) * kCells + c(y[p])) * kCells + c(x[p]);
    };
    std::sort(idx.begin(), idx.end(), [&](auto a, auto b) { return cell(a) < cell(b); });
    auto permute = [&](std::vector<double>& v) {
      std::vector<double> w(n);
      for (std::size_t p = 0; p < n; ++p) w[p] = v[idx[p]];
      v.swap(w);
    };
    permute(x), permute(y), permute(z), permute(q);
    st.compute(KernelKind::Trilinear, dec, layout, x, y, z, n);
    out.assign(7, std::vector<double>(n));
  }
};

void BM_Sample7(benchmark::State& state) {
  StepSetup s(static_cast<std::size_t>(state.range(0)));
  const CellField* in[7];
  double* o[7];
  for (int k = 0; k < 7; ++k) in[k] = &s.f[k], o[k] = s.out[k].data();
  for (auto _ : state) {
    if (state.range(1)) {
      interpolate(s.st, in, o);
    } else {
      for (int k = 0; k < 7; ++k) interpolate(s.st, s.f[k], s.out[k]);
    }
    benchmark::DoNotOptimize(o[0]);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetLabel(state.range(1) ? "fused" : "one pass a field");
}

void BM_Deposit5(benchmark::State& state) {
  StepSetup s(static_cast<std::size_t>(state.range(0)));
  const double* b = s.out[0].data();
  const DepositTerm terms[5] = {{s.q.data(), nullptr, 1.0, &s.f[0]},
                                {s.q.data(), nullptr, 2.0, &s.f[1]},
                                {s.q.data(), b, 2.0, &s.f[2]},
                                {s.q.data(), b, 2.0, &s.f[3]},
                                {s.q.data(), b, 2.0, &s.f[4]}};
  for (auto _ : state) {
    if (state.range(1)) {
      deposit(s.st, terms);
    } else {
      for (const auto& t : terms)
        if (t.b)
          depositProduct(s.st, s.q, s.out[0], t.scale, *t.f);
        else
          deposit(s.st, s.q, t.scale, *t.f);
    }
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetLabel(state.range(1) ? "fused" : "one pass a field");
}

void BM_Drag(benchmark::State& state) {
  const auto law = static_cast<DragLaw>(state.range(1));
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> epsD(0.4, 1.0), slipD(0.0, 2.0);
  std::vector<double> eps(n), slip(n);
  for (std::size_t p = 0; p < n; ++p) eps[p] = epsD(rng), slip[p] = slipD(rng);
  for (auto _ : state) {
    double acc = 0;
    for (std::size_t p = 0; p < n; ++p)
      acc += dragCoefficient(law, eps[p], 1e-3, slip[p], 1.2, 1.5e-5);
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetLabel(dragLawName(law));
}

}  // namespace

// Args: {particles, kernel (0 centroid, 1 trilinear)}
BENCHMARK(BM_StencilCompute)->Args({100000, 0})->Args({100000, 1})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Deposit)->Args({100000, 0})->Args({100000, 1})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Interpolate)->Args({100000, 0})->Args({100000, 1})->Unit(benchmark::kMicrosecond);
// Args: {particles, fused}; 1e5 particles on the 64^3 block (0.4 a cell) and 1e6 (3.8 a cell)
BENCHMARK(BM_Sample7)
    ->Args({100000, 0})
    ->Args({100000, 1})
    ->Args({1000000, 0})
    ->Args({1000000, 1})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Deposit5)
    ->Args({100000, 0})
    ->Args({100000, 1})
    ->Args({1000000, 0})
    ->Args({1000000, 1})
    ->Unit(benchmark::kMicrosecond);
// Args: {particles, law (0 stokes, 1 difelice, 2 gidaspow, 3 beetstra)}
BENCHMARK(BM_Drag)
    ->Args({100000, 0})
    ->Args({100000, 1})
    ->Args({100000, 2})
    ->Args({100000, 3})
    ->Unit(benchmark::kMicrosecond);
