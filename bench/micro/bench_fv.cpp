// Fluid microbenchmarks. Iterations are fixed (every rank runs the same number; the solvers
// exchange messages) and the time is the slowest rank's (manual time).
//
// BM_PressureSolve/n/kind: the pressure equation alone on an n^3 cell-centred unit cube with
//   homogeneous Dirichlet faces (the 7-point Laplacian the fluid assembles for eps = 1, K = 0),
//   right-hand side sin(pi x) sin(pi y) sin(pi z), zero initial guess, relative tolerance 1e-6;
//   kind 0 = PCG + PFMG, 1 = PCG + SMG. Counter `iterations`: PCG iterations (PFMG's should be
//   nearly independent of n).
// BM_PressureOptions/variant: the same equation on the channel's 250 x 50 x 50 grid with the
//   PFMG options of one row of its table (relaxation, skip, coarse operators, PCG or not):
//   set-up and solve time of each (docs/fv.md, "Pressure solver options").
// BM_FluidChannelStep/n: one fluid step of bench/cases/fluid-channel.json with 5n x n x n cells
//   (n = 50 is the 625,000-cell benchmark), after 3 warm-up steps. Counters: seconds per step
//   (the manual time), cell_steps_per_s, pressure iterations per step, peak RSS bytes per cell.
#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>
#include <string>
#include <vector>

#include "coloc/core/run_config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/fv/fluid.hpp"
#include "coloc/partition/setup.hpp"
#include "pressure_solver.hpp"

namespace {

using namespace coloc;

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// The pressure equation on an nx x ny x nz box of unit spacing-scaled cells (see the header).
void solvePressure(benchmark::State& state, Int3 n, fv::PressureSolver::Options opt) {
  GlobalGrid g;
  g.cells = n;
  g.length = {1.0, static_cast<double>(n[1]) / n[0], static_cast<double>(n[2]) / n[0]};
  const auto dec = Decomposition::uniform(Comm::world(), g);
  opt.tol = 1e-6;
  opt.maxIter = 200;
  fv::PressureSolver ps(dec, opt);
  const Int3 c = dec.cells();
  const std::size_t cells = static_cast<std::size_t>(dec.ownedCellCount());
  std::vector<double> A(7 * cells), b(cells), x(cells, 0.0);
  const double h = 1.0 / n[0], w = 1.0 / (h * h);
  std::size_t r = 0;
  for (int k = 0; k < c[2]; ++k)
    for (int j = 0; j < c[1]; ++j)
      for (int i = 0; i < c[0]; ++i, ++r) {
        const int gi[3] = {dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k};
        double diag = 0;
        for (int a = 0; a < 3; ++a)
          for (int s = 0; s < 2; ++s) {
            const bool wall = s == 0 ? gi[a] == 0 : gi[a] == n[a] - 1;
            A[7 * r + 1 + 2 * a + s] = wall ? 0.0 : -w;
            diag += wall ? 2 * w : w;  // Dirichlet at the face, half a cell away
          }
        A[7 * r] = diag;
        b[r] = std::sin(M_PI * (gi[0] + 0.5) / n[0]) * std::sin(M_PI * (gi[1] + 0.5) / n[1]) *
               std::sin(M_PI * (gi[2] + 0.5) / n[2]);
      }
  // The set-up as a coupled step repeats it (new coefficients on the same grid, every step):
  // the mean of three after a first one that also builds hypre's communication packages.
  ps.setMatrix(A);
  constexpr int kSetups = 3;
  dec.comm().barrier();
  const double t0 = MPI_Wtime(), c0 = threadCpuSeconds();
  for (int s = 0; s < kSetups; ++s) ps.setMatrix(A);
  const double setup = dec.comm().max(MPI_Wtime() - t0) / kSetups;
  const double setupCpu = dec.comm().max(threadCpuSeconds() - c0) / kSetups;
  int its = 0;
  for (auto _ : state) {
    std::fill(x.begin(), x.end(), 0.0);
    dec.comm().barrier();
    const double t1 = MPI_Wtime();
    its = ps.solve(b, x, 0.0);
    state.SetIterationTime(dec.comm().max(MPI_Wtime() - t1));
  }
  state.counters["ranks"] = dec.size();
  state.counters["cells"] = static_cast<double>(g.cellCount());
  state.counters["iterations"] = its;
  state.counters["setup_s"] = setup;
  state.counters["setup_cpu_s"] = setupCpu;  // busy: bench/scripts/model.py on a loaded machine
  state.counters["rel_residual"] = ps.lastRelativeResidual();
  // the block faces shared with other ranks (cells, largest rank): hypre's per-rank overhead
  // grows with them (bench/scripts/model.py)
  double face = 0;
  for (int a = 0; a < 3; ++a) {
    const int sides = (dec.neighbour(a, -1) >= 0) + (dec.neighbour(a, +1) >= 0);
    face += sides * static_cast<double>(c[(a + 1) % 3]) * c[(a + 2) % 3];
  }
  state.counters["face_cells"] = dec.comm().max(face);
}

fv::PressureSolver::Options kindOptions(long long kindArg) {
  fv::PressureSolver::Options o;
  o.kind = kindArg == 0 ? fv::PressureSolver::Kind::Pfmg : fv::PressureSolver::Kind::Smg;
  return o;
}

void BM_PressureSolve(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  solvePressure(state, {n, n, n}, kindOptions(state.range(1)));
}

/// BM_PressureSolveBox/nx/ny/nz/kind: the same on a box (the benchmark cases' grids).
void BM_PressureSolveBox(benchmark::State& state) {
  solvePressure(state,
                {static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                 static_cast<int>(state.range(2))},
                kindOptions(state.range(3)));
}

/// BM_PressureOptions/variant: the channel's grid (250 x 50 x 50), PCG + PFMG with the options
/// of the row `variant` of the table below (the label names it): set-up and solve cost of each.
void BM_PressureOptions(benchmark::State& state) {
  using PS = fv::PressureSolver;
  constexpr auto Rbgs = PS::Relax::RbgsSymmetric, WJac = PS::Relax::WeightedJacobi;
  constexpr auto NonGalerkin = PS::Rap::NonGalerkin;
  struct Variant {
    const char* name;
    PS::Options o;
  };
  const Variant variants[] = {
      {"rbgs (before issue 16)", {.relax = Rbgs, .skipRelax = false}},
      {"weighted_jacobi", {.relax = WJac, .skipRelax = false}},
      {"rbgs skip (default)", {.relax = Rbgs, .skipRelax = true}},
      {"rbgs non_galerkin", {.relax = Rbgs, .rap = NonGalerkin, .skipRelax = false}},
      {"weighted_jacobi skip (fluid-channel)", {.relax = WJac, .skipRelax = true}},
      {"rbgs skip non_galerkin", {.relax = Rbgs, .rap = NonGalerkin, .skipRelax = true}},
      {"weighted_jacobi skip non_galerkin", {.relax = WJac, .rap = NonGalerkin, .skipRelax = true}},
      {"rbgs, no pcg", {.pcg = false, .relax = Rbgs, .skipRelax = false}},
      {"rbgs non_galerkin, no pcg",
       {.pcg = false, .relax = Rbgs, .rap = NonGalerkin, .skipRelax = false}},
  };
  const auto& v = variants[state.range(0)];
  state.SetLabel(v.name);
  solvePressure(state, {250, 50, 50}, v.o);
}

void BM_FluidChannelStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Schema s;
  declareRunConfig(s);
  declareDomainConfig(s);
  fv::declareConfig(s);
  const Config cfg = Config::load(Comm::world(), COLOC_SOURCE_DIR "/bench/cases/fluid-channel.json",
                                  {"domain.cells=[" + std::to_string(5 * n) + "," +
                                   std::to_string(n) + "," + std::to_string(n) + "]"},
                                  s);
  const Decomposition dec = decompositionFromConfig(Comm::world(), cfg);
  Timers timers;
  fv::FluidSolver solver(dec, cfg, timers);
  for (int w = 0; w < 3; ++w) solver.step(solver.nextDt());
  const Json d0 = solver.diagnostics();
  const double it0 = d0["pressure"]["iterations_avg"].get<double>() * 3;
  long long steps = 0;
  double busy = 0;
  for (auto _ : state) {
    dec.comm().barrier();
    const double t0 = MPI_Wtime();
    solver.step(solver.nextDt());
    const double dt = dec.comm().max(MPI_Wtime() - t0);
    state.SetIterationTime(dt);
    busy += dt;
    ++steps;
  }
  const Json d = solver.diagnostics();
  const double its = d["pressure"]["iterations_avg"].get<double>() * (3 + steps) - it0;
  const double cells = static_cast<double>(dec.grid().cellCount());
  state.counters["ranks"] = dec.size();
  state.counters["cells"] = cells;
  state.counters["cell_steps_per_s"] = cells * steps / busy;
  state.counters["pressure_its_per_step"] = its / steps;
  state.counters["cfl"] = d["fluid"]["cfl_last"].get<double>();
  state.counters["rss_bytes_per_cell"] =
      static_cast<double>(dec.comm().sum(peakRssBytes())) / cells;
  for (Phase p : {Phase::FluidMomentum, Phase::FluidBoundary, Phase::FluidHalo,
                  Phase::FluidPressureAssemble, Phase::FluidPressureSolve, Phase::FluidProject})
    state.counters[std::string(phaseName(p))] = dec.comm().max(timers.seconds(p)) / (3 + steps);
}

}  // namespace

BENCHMARK(BM_PressureSolve)
    ->Args({32, 0})
    ->Args({64, 0})
    ->Args({128, 0})
    ->Args({64, 1})
    ->Iterations(3)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PressureSolveBox)
    ->Args({72, 6, 72, 0})     // case3-small
    ->Args({110, 22, 22, 0})   // case2-small
    ->Args({240, 20, 240, 0})  // case 3
    ->Iterations(3)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PressureOptions)
    ->DenseRange(0, 8)
    ->Iterations(3)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FluidChannelStep)
    ->Arg(10)
    ->Arg(20)
    ->Arg(50)
    ->Iterations(5)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
