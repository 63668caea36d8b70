// DEM microbenchmarks and the settled-bed benchmark (issue 4).
//
//  BM_Contact<Hertz|Linear>/N : the contact-force kernel alone on N synthetic contacts
//                               (items = contacts; ns per contact).
//  BM_NeighbourBuild/N         : a full rebuild (migration, sort by bin, ghosts, bins, Verlet
//                               lists) of a random dense packing of N spheres; items = particles.
//  BM_ForceLoop/N             : one force evaluation over the same packing; items = particles.
//  BM_DemBed                  : bench/cases/dem-bed.json (100,000 spheres; override the file with
//                               DEM_BED_CASE): settles DEM_BED_SETTLE steps (default 3000), then
//                               times 100 sub-steps per iteration. Counters: particle_steps_per_s,
//                               contacts_per_particle, bytes_per_particle (the solver's own
//                               arrays), rss_per_particle (peak RSS growth from before the solver
//                               was built), rss_run_per_particle (resident growth at the end,
//                               after the state file's buffers are gone), and the time split of
//                               the timed steps; the solver's bytes by part go to stderr.
//                               DEM_BED_DUMP=file writes the settled bed as a LIGGGHTS data file.
//                               DEM_BED_SAVE=file writes the settled DemState (particles,
//                               forces, contact histories; binary; on P > 1 ranks each rank's
//                               rows to file.r<rank>), DEM_BED_LOAD=file restores it
//                               instead of settling (rank r reads rows [r n/P, (r+1) n/P); the
//                               restoring constructor sends them to their owners).
// Benchmarks that exchange MPI messages use fixed iteration counts so every rank runs the same
// number; the reported time is the slowest rank's (manual time).
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

#include "coloc/core/run_config.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/setup.hpp"
#include "contact.hpp"
#include "rng.hpp"

namespace {

using coloc::dem::detail::Model;

template <Model M>
void contactKernel(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  coloc::dem::detail::Material mat;
  mat.young = 5e6;
  mat.poisson = 0.45;
  mat.restitution = 0.9;
  mat.friction = 0.5;
  const auto c = coloc::dem::detail::mix(mat, mat, 1e3, 2.0 / 7.0);
  std::vector<double> nrm(3 * n), vr(3 * n), ws(3 * n), wr(3 * n), sh(3 * n, 0.0), dl(n);
  for (std::size_t i = 0; i < n; ++i) {
    double v[3];
    for (int k = 0; k < 3; ++k) v[k] = 2 * coloc::dem::detail::uniform01(1, i, k) - 1;
    const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + 1e-12;
    for (int k = 0; k < 3; ++k) {
      nrm[3 * i + k] = v[k] / len;
      vr[3 * i + k] = 0.1 * (2 * coloc::dem::detail::uniform01(2, i, k) - 1);
      ws[3 * i + k] = 1e-4 * (2 * coloc::dem::detail::uniform01(3, i, k) - 1);
      wr[3 * i + k] = 0.2 * (2 * coloc::dem::detail::uniform01(4, i, k) - 1);
    }
    dl[i] = 1e-6 * (1 + coloc::dem::detail::uniform01(5, i, 0));
  }
  const double m = 2500 * 4.0 / 3.0 * M_PI * 1.25e-10;
  double F[3] = {0, 0, 0}, T[3] = {0, 0, 0};
  for (auto _ : state) {
    for (std::size_t i = 0; i < n; ++i)
      coloc::dem::detail::contactForce<M>(c, 1e-5, true, &nrm[3 * i], dl[i], 2.5e-4, 0.5 * m, 5e-4,
                                          &vr[3 * i], &ws[3 * i], &wr[3 * i], &sh[3 * i], F, T);
    benchmark::DoNotOptimize(F);
    benchmark::DoNotOptimize(T);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<long long>(state.iterations()) * static_cast<long long>(n));
}

coloc::Schema schema() {
  coloc::Schema s;
  coloc::declareRunConfig(s);
  coloc::declareDomainConfig(s);
  coloc::dem::declareConfig(s);
  return s;
}

/// A dense random packing of about n spheres of d = 1 mm (periodic box, sites of 1.05 d).
std::string packingCase(long n) {
  const double site = 0.00105;
  const long side = static_cast<long>(std::ceil(std::cbrt(static_cast<double>(n) / 0.9)));
  const double len = static_cast<double>(side) * site;
  const long cells = std::max(1L, static_cast<long>(len / 0.0025));
  std::ostringstream c;
  c.precision(17);
  c << R"({"domain": {"length": [)" << len << ", " << len << ", " << len << R"(], "cells": [)"
    << cells << ", " << cells << ", " << cells
    << R"(], "periodic": {"x": true, "y": true, "z": true}},
    "particles": {"dt": 1e-5, "materials": [{"density": 2500, "young": 5e6, "poisson": 0.45,
      "restitution": 0.9, "friction": 0.5}],
      "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [)"
    << len << ", " << len << ", " << len << R"(], "count": )" << n
    << R"(, "radius": 0.0005, "gap": 0.0}]}})";
  return c.str();
}

struct Packing {
  coloc::Config cfg;
  coloc::Decomposition dec;
  coloc::Timers timers;
  std::unique_ptr<coloc::dem::DemSolver> dem;
  explicit Packing(const std::string& text)
      : cfg(coloc::Config::fromText(text, "bench", {}, schema())),
        dec(coloc::decompositionFromConfig(coloc::Comm::world(), cfg)) {
    dem = std::make_unique<coloc::dem::DemSolver>(dec, cfg, timers);
  }
};

void BM_NeighbourBuild(benchmark::State& state) {
  Packing p(packingCase(state.range(0)));
  const auto& comm = p.dec.comm();
  for (auto _ : state) {
    comm.barrier();
    const double t0 = comm.wtime();
    p.dem->rebuildNow();
    state.SetIterationTime(comm.max(comm.wtime() - t0));
  }
  const auto d = p.dem->diagnostics();
  state.SetItemsProcessed(static_cast<long long>(state.iterations()) * p.dem->globalCount());
  state.counters["neighbors_per_particle"] = d["neighbors_per_particle"].get<double>();
  state.counters["ranks"] = p.dec.size();
}

void BM_ForceLoop(benchmark::State& state) {
  Packing p(packingCase(state.range(0)));
  const auto& comm = p.dec.comm();
  for (auto _ : state) {
    comm.barrier();
    const double t0 = comm.wtime();
    p.dem->computeForcesNow();
    state.SetIterationTime(comm.max(comm.wtime() - t0));
  }
  const auto d = p.dem->diagnostics();
  state.SetItemsProcessed(static_cast<long long>(state.iterations()) * p.dem->globalCount());
  state.counters["neighbors_per_particle"] = d["neighbors_per_particle"].get<double>();
  state.counters["ranks"] = p.dec.size();
}

constexpr int kRec = 22;  // id, material, radius, mass, x, v, omega, f, torque, fExt

void saveState(const coloc::dem::DemState& st, const std::string& file) {
  std::vector<double> buf = {static_cast<double>(st.particles.nOwned),
                             static_cast<double>(st.contacts.size()), st.time,
                             static_cast<double>(st.steps), static_cast<double>(st.rebuilds)};
  const auto& q = st.particles;
  for (std::size_t i = 0; i < q.nOwned; ++i) {
    buf.push_back(static_cast<double>(q.id[i]));
    buf.push_back(q.material[i]);
    buf.push_back(q.radius[i]);
    buf.push_back(q.mass[i]);
    for (const auto* a : {&q.x, &q.v, &q.omega, &q.f, &q.torque, &q.fExt})
      for (int k = 0; k < 3; ++k) buf.push_back((*a)[k][i]);
  }
  for (const auto& c : st.contacts) {
    buf.push_back(static_cast<double>(c.holder));
    buf.push_back(static_cast<double>(c.partner));
    buf.insert(buf.end(), c.shear.begin(), c.shear.end());
  }
  std::ofstream out(file, std::ios::binary);
  out.write(reinterpret_cast<const char*>(buf.data()),
            static_cast<std::streamsize>(buf.size() * sizeof(double)));
}

coloc::dem::DemState loadState(const std::string& file, int rank, int size) {
  std::ifstream in(file, std::ios::binary);
  double h[5];
  in.read(reinterpret_cast<char*>(h), sizeof h);
  const auto n = static_cast<std::size_t>(h[0]), nc = static_cast<std::size_t>(h[1]);
  std::vector<double> buf(n * kRec + 5 * nc);
  in.read(reinterpret_cast<char*>(buf.data()),
          static_cast<std::streamsize>(buf.size() * sizeof(double)));
  if (!in) throw coloc::Error("DEM_BED_LOAD: cannot read " + file);
  coloc::dem::DemState st;
  st.time = h[2];
  st.steps = static_cast<long long>(h[3]);
  st.rebuilds = static_cast<long long>(h[4]);
  const auto P = static_cast<std::size_t>(size), r = static_cast<std::size_t>(rank);
  auto& q = st.particles;
  for (std::size_t i = r * n / P; i < (r + 1) * n / P; ++i) {
    const double* b = &buf[i * kRec];
    q.id.push_back(static_cast<std::int64_t>(b[0]));
    q.material.push_back(static_cast<int>(b[1]));
    q.radius.push_back(b[2]);
    q.mass.push_back(b[3]);
    int o = 4;
    for (auto* a : {&q.x, &q.v, &q.omega, &q.f, &q.torque, &q.fExt})
      for (int k = 0; k < 3; ++k) (*a)[k].push_back(b[o++]);
    ++q.nOwned;
  }
  for (std::size_t c = r * nc / P; c < (r + 1) * nc / P; ++c) {
    const double* b = &buf[n * kRec + 5 * c];
    coloc::dem::ContactHistory ch;
    ch.holder = static_cast<std::int64_t>(b[0]);
    ch.partner = static_cast<std::int64_t>(b[1]);
    ch.shear = {b[2], b[3], b[4]};
    st.contacts.push_back(ch);
  }
  return st;
}

/// The resident set now (VmRSS, /proc/self/statm), bytes.
long long residentBytes() {
  std::ifstream in("/proc/self/statm");
  long long pages = 0, rss = 0;
  in >> pages >> rss;
  return rss * 4096;
}

void BM_DemBed(benchmark::State& state) {
  const char* env = std::getenv("DEM_BED_CASE");
  const std::string path = env ? env : COLOC_SOURCE_DIR "/bench/cases/dem-bed.json";
  const char* settleEnv = std::getenv("DEM_BED_SETTLE");
  const int settle = settleEnv ? std::atoi(settleEnv) : 3000;
  const auto comm = coloc::Comm::world();
  const long long rss0 = comm.max(coloc::peakRssBytes());
  const long long rssStart = residentBytes();
  const auto cfg = coloc::Config::load(comm, path, {}, schema());
  const auto dec = coloc::decompositionFromConfig(comm, cfg);
  coloc::Timers timers;
  const char* load = std::getenv("DEM_BED_LOAD");
  auto demPtr = load ? std::make_unique<coloc::dem::DemSolver>(
                           dec, cfg, timers, loadState(load, dec.rank(), dec.size()))
                     : std::make_unique<coloc::dem::DemSolver>(dec, cfg, timers);
  auto& dem = *demPtr;
  // the state file's buffers are freed by now: their pages go back to the system, so that the
  // resident growth at the end (rss_run_per_particle) is the solver's, not the loader's leftovers
  if (load) malloc_trim(0);
  for (int s = 0; s < settle; ++s) dem.substep();
  // (on P > 1 ranks each rank's own rows to FILE.r<rank>: a comparison of two builds at the same
  // rank count, file by file)
  if (const char* save = std::getenv("DEM_BED_SAVE"))
    saveState(dem.saveState(),
              dec.size() == 1 ? std::string(save) : save + (".r" + std::to_string(dec.rank())));
  // DEM_BED_DUMP=file (1 rank): the settled bed as a LIGGGHTS/LAMMPS data file (atom_style
  // granular), for the side-by-side comparison of docs/dem.md.
  if (const char* dump = std::getenv("DEM_BED_DUMP"); dump && dec.size() == 1) {
    const auto& p = dem.particles();
    const auto& g = dec.grid();
    std::ofstream out(dump);
    out.precision(17);
    out << "coloc dem-bed settled state\n\n" << p.nOwned << " atoms\n1 atom types\n\n";
    const char* ax[3] = {"x", "y", "z"};
    for (int d = 0; d < 3; ++d)
      out << g.origin[d] << " " << g.origin[d] + g.length[d] << " " << ax[d] << "lo " << ax[d]
          << "hi\n";
    out << "\nAtoms\n\n";
    for (std::size_t i = 0; i < p.nOwned; ++i)
      out << p.id[i] + 1 << " 1 " << 2 * p.radius[i] << " "
          << p.mass[i] / (4.0 / 3.0 * M_PI * p.radius[i] * p.radius[i] * p.radius[i]) << " "
          << p.x[0][i] << " " << p.x[1][i] << " " << p.x[2][i] << "\n";
    out << "\nVelocities\n\n";
    for (std::size_t i = 0; i < p.nOwned; ++i)
      out << p.id[i] + 1 << " " << p.v[0][i] << " " << p.v[1][i] << " " << p.v[2][i] << " "
          << p.omega[0][i] << " " << p.omega[1][i] << " " << p.omega[2][i] << "\n";
  }
  timers.reset();
  const int perIter = 100;
  double wall = 0;
  for (auto _ : state) {
    comm.barrier();
    const double t0 = comm.wtime();
    for (int s = 0; s < perIter; ++s) dem.substep();
    const double dt = comm.max(comm.wtime() - t0);
    state.SetIterationTime(dt);
    wall += dt;
  }
  const long long n = dem.globalCount();
  const auto d = dem.diagnostics();
  const long long rss1 = comm.max(coloc::peakRssBytes());
  const double steps = static_cast<double>(state.iterations()) * perIter;
  state.counters["ranks"] = dec.size();
  state.counters["particles"] = static_cast<double>(n);
  state.counters["particle_steps_per_s"] = static_cast<double>(n) * steps / wall;
  state.counters["contacts_per_particle"] = d["contacts_per_particle"].get<double>();
  state.counters["neighbors_per_particle"] = d["neighbors_per_particle"].get<double>();
  state.counters["bytes_per_particle"] = d["bytes_per_particle"].get<double>();
  if (comm.rank() == 0 && d.contains("bytes_by_part")) {  // where the bytes go
    std::ostringstream os;
    os << "bytes per particle by part:";
    for (const auto& [k, b] : d["bytes_by_part"].items()) os << " " << k << " " << b.get<double>();
    std::fprintf(stderr, "%s\n", os.str().c_str());
  }
  state.counters["rss_per_particle"] =
      static_cast<double>(rss1 - rss0) * dec.size() / static_cast<double>(n);
  // resident now, after the timed steps (the restored runs' peak includes the state file)
  state.counters["rss_run_per_particle"] =
      static_cast<double>(comm.sum(residentBytes()) - comm.sum(rssStart)) / static_cast<double>(n);
  state.counters["rebuilds"] = static_cast<double>(dem.rebuildCount());
  state.counters["prunes"] = d["prunes"].get<double>();
  const auto share = [&](coloc::Phase ph) { return comm.max(timers.seconds(ph)) / wall; };
  state.counters["f_neighbour"] = share(coloc::Phase::DemNeighbour);
  state.counters["f_force"] = share(coloc::Phase::DemForce);
  state.counters["f_integrate"] = share(coloc::Phase::DemIntegrate);
  state.counters["f_ghost"] = share(coloc::Phase::DemGhost);
  state.counters["f_migrate"] = share(coloc::Phase::DemMigrate);
}

}  // namespace

BENCHMARK(contactKernel<Model::HertzMindlin>)->Name("BM_ContactHertz")->Arg(4096)->Arg(65536);
BENCHMARK(contactKernel<Model::Linear>)->Name("BM_ContactLinear")->Arg(4096)->Arg(65536);
BENCHMARK(BM_NeighbourBuild)
    ->Arg(10000)
    ->Arg(100000)
    ->Iterations(10)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ForceLoop)
    ->Arg(10000)
    ->Arg(100000)
    ->Iterations(20)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DemBed)->Iterations(5)->UseManualTime()->Unit(benchmark::kMillisecond);
