// The force pass's paths give the same bits (issue 48; docs/dem.md, "Force pass"):
//  - pass 1 entry by entry (particles.force_isa = scalar) and eight entries at a time on
//    AVX-512 (avx512, where the CPU has it), each with the pruned inner list off
//    (particles.prune_margin = 0) and on with two margins: after 300 sub-steps of a bidisperse
//    dense gas of two materials (rolling resistance on one) between two walls, with rebuilds,
//    re-prunes, contacts starting and ending and rows longer than a keep mask, every variant's
//    state (positions, velocities, spins, forces, torques, contact histories) and temperatures and
//    heat rates are those of the first, byte for byte; the inner list was used (prunes counted,
//    fewer than the force passes);
//  - contact conduction inside the force pass equals the separate pass (HeatTransfer::conduct,
//    which a frozen sub-step runs at the same positions and temperatures) bit for bit.
// RANKS 1 2 3: the same at every rank count of the test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "dem_test_util.hpp"
#include "heat_test_util.hpp"

namespace {

using demtest::Case;

/// The gas: two simple-cubic lattices of spacing 0.995 mm (12 x 12 x 8 each) of diameters 0.8
/// and 1.0 mm drawn per particle (1:1), so that the large ones start slightly pressed together,
/// with random velocities of ~1 m/s; material 0 below at 350 K, material 1 (rolling friction)
/// above at 300 K, walls at 400 K on z, periodic in x and y; a skin of 1.2 diameters, so that
/// rows are longer than a keep mask (up to ~30 entries).
std::string gas(const std::string& isa, double margin) {
  char buf[4096];
  std::snprintf(buf, sizeof buf, R"({
  "gravity": [0, 0, -9.81],
  "domain": {"length": [0.01194, 0.01194, 0.018], "cells": [4, 4, 6],
             "periodic": {"x": true, "y": true}},
  "particles": {
    "dt": 5e-6, "skin": 1.2, "heat": true, "wall_temperature": 400,
    "force_isa": "%s", "prune_margin": %.17g,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.7,
                   "friction": 0.5, "heat_capacity": 800, "conductivity": 1},
                  {"density": 2000, "young": 1e7, "poisson": 0.25, "restitution": 0.8,
                   "friction": 0.3, "rolling_friction": 0.05, "heat_capacity": 800,
                   "conductivity": 3}],
    "sources": [{"type": "lattice", "material": 0, "lo": [0.0004975, 0.0004975, 0.0005],
                 "counts": [12, 12, 8], "spacing": [0.000995, 0.000995, 0.000995],
                 "temperature": 350, "velocity": [0.2, -0.1, -0.5], "velocity_spread": 1.0,
                 "size": {"type": "discrete", "diameters": [0.0008, 0.001]}},
                {"type": "lattice", "material": 1, "lo": [0.0004975, 0.0004975, 0.0085],
                 "counts": [12, 12, 8], "spacing": [0.000995, 0.000995, 0.000995],
                 "temperature": 300, "velocity": [-0.1, 0.2, -0.5], "velocity_spread": 1.0,
                 "size": {"type": "discrete", "diameters": [0.0008, 0.001]}}]
  }
})",
                isa.c_str(), margin);
  return buf;
}
constexpr long kN = 2304;

bool hasAvx512() {
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
}

/// Everything a run's result is made of, by id over all ranks (collective): per particle id,
/// x, v, omega, f, torque, temperature, heat rate; then the contact histories (holder, partner,
/// shear) sorted.
std::vector<double> result(Case& c) {
  const auto& p = c.p();
  const auto& comm = c.dec.comm();
  constexpr int kW = 17;
  std::vector<double> t(static_cast<std::size_t>(kW * kN), 0.0);
  const auto& T = p.field("temperature");
  const auto& Q = p.field("heat_rate");
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    double* r = &t[static_cast<std::size_t>(kW * p.id[i])];
    int o = 0;
    for (const auto* a : {&p.x, &p.v, &p.omega, &p.f, &p.torque})
      for (int k = 0; k < 3; ++k) r[o++] = (*a)[k][i];
    r[o++] = T[i];
    r[o++] = Q[i];
  }
  comm.sumInPlace(std::span<double>(t));
  const auto st = c.dem->saveState();
  std::vector<double> h;
  for (const auto& ch : st.contacts) {
    h.push_back(static_cast<double>(ch.holder));
    h.push_back(static_cast<double>(ch.partner));
    h.insert(h.end(), ch.shear.begin(), ch.shear.end());
  }
  const auto counts = comm.allgather(static_cast<int>(h.size()));
  std::vector<int> displ;
  std::vector<double> all(static_cast<std::size_t>(coloc::Comm::displacements(counts, displ)));
  MPI_Allgatherv(h.data(), static_cast<int>(h.size()), MPI_DOUBLE, all.data(), counts.data(),
                 displ.data(), MPI_DOUBLE, comm.raw());
  std::vector<std::size_t> idx(all.size() / 5);
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    return all[5 * a] != all[5 * b] ? all[5 * a] < all[5 * b] : all[5 * a + 1] < all[5 * b + 1];
  });
  for (const std::size_t k : idx) t.insert(t.end(), all.begin() + 5 * k, all.begin() + 5 * k + 5);
  return t;
}

struct Outcome {
  std::vector<double> result;
  long long rebuilds, prunes;
  double contacts, neighbours;  // per particle, at the end
};

Outcome runVariant(const std::string& isa, double margin, int steps) {
  Case c(gas(isa, margin));
  for (int s = 0; s < steps; ++s) c.dem->substep();
  const auto d = c.dem->diagnostics();
  return {result(c), d["rebuilds"].get<long long>(), d["prunes"].get<long long>(),
          d["contacts_per_particle"].get<double>(), d["neighbors_per_particle"].get<double>()};
}

TEST(DemForcePaths, EveryPathGivesTheSameBits) {
  constexpr int kSteps = 300;
  const Outcome ref = runVariant("scalar", 0, kSteps);
  EXPECT_GE(ref.rebuilds, 2);
  EXPECT_EQ(ref.prunes, 0);
  std::vector<std::string> isas = {"scalar"};
  if (hasAvx512()) isas.emplace_back("avx512");
  int compared = 0;
  for (const auto& isa : isas)
    for (const double margin : {0.0, 0.05, 0.1}) {
      if (isa == "scalar" && margin == 0) continue;
      const Outcome r = runVariant(isa, margin, kSteps);
      SCOPED_TRACE(isa + ", prune_margin " + std::to_string(margin));
      ASSERT_EQ(r.result.size(), ref.result.size());
      EXPECT_EQ(std::memcmp(r.result.data(), ref.result.data(), r.result.size() * sizeof(double)),
                0);
      EXPECT_EQ(r.rebuilds, ref.rebuilds);
      if (coloc::Comm::world().isRoot())
        std::printf("%s %.2f: %lld prunes\n", isa.c_str(), margin, r.prunes);
      if (margin > 0) {
        // pruned at every rebuild and in between (the margin closes before the skin), yet the
        // inner list served most passes
        EXPECT_GT(r.prunes, r.rebuilds + 1);
        EXPECT_LT(r.prunes, kSteps / 2);
      } else {
        EXPECT_EQ(r.prunes, 0);
      }
      ++compared;
    }
  EXPECT_EQ(compared, hasAvx512() ? 5 : 2);
  if (coloc::Comm::world().isRoot())
    std::printf(
        "%d variants equal to the scalar pass without pruning (%lld rebuilds; at the end %.2f "
        "contacts and %.1f list entries a particle)\n",
        compared, ref.rebuilds, ref.contacts, ref.neighbours);
}

// Conduction in the force pass against the separate pass at the same positions and temperatures:
// the temperatures the last sub-step's force pass read are written back after it, then a frozen
// sub-step (which runs HeatTransfer::conduct at the same positions, no force pass, and refreshes
// the ghosts' temperatures) must reproduce the heat rates bit for bit.
TEST(DemForcePaths, ConductionInsideTheForcePassEqualsItsOwnPass) {
  for (const char* isa : {"scalar", "widest"}) {
    Case c(gas(isa, 0.05));
    for (int s = 0; s < 119; ++s) c.dem->substep();
    const auto Tread = demtest::fieldById(c.p(), c.dec.comm(), kN);
    c.dem->substep();
    const auto Q0 = demtest::fieldById(c.p(), c.dec.comm(), kN, "heat_rate");
    double qMax = 0;
    for (const double q : Q0) qMax = std::max(qMax, std::abs(q));
    EXPECT_GT(qMax, 0.0);
    EXPECT_NE(demtest::fieldById(c.p(), c.dec.comm(), kN), Tread) << "no temperature moved";
    auto& p = c.p();
    auto& T = p.field("temperature");
    for (std::size_t i = 0; i < p.nOwned; ++i) T[i] = Tread[static_cast<std::size_t>(p.id[i])];
    c.dem->setFrozen(true);
    c.dem->substep();
    EXPECT_EQ(demtest::fieldById(c.p(), c.dec.comm(), kN, "heat_rate"), Q0) << isa;
  }
}

}  // namespace
