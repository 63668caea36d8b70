// Particle temperature and conduction through contacts (issue 31, DEM part; docs/heat.md,
// "Particles").
//  - two pairs of spheres of two materials in a periodic chain along x (each sphere touches its
//    two neighbours, of the other material, at the same overlap: forces cancel, nothing moves)
//    equilibrate at the two-body rate d(dT)/dt = -2 H (1/C1 + 1/C2) dT, H = 2 k_eff a,
//    a = sqrt(R* delta) (Batchelor & O'Brien 1977): within 2 % (contacts straddle the rank faces
//    and the periodic face on 2+ ranks);
//  - a sphere resting on a floor at its Hertz equilibrium overlap relaxes to the wall's
//    temperature at H_w / C: within 2 %;
//  - a closed box with a hot half, many particles in contact: the enthalpy is constant to
//    1e-12 relative (adiabatic walls); with walls at a fixed temperature, its change equals the
//    accumulated wall heat to 1e-12 relative;
//  - the temperatures of that bed agree with a serial run to round-off (process grid, tiled);
//  - save/restore continues them and the energy accounts bit for bit; particles.heat off moves
//    no temperature;
//  - a material without heat_capacity is refused naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "coloc/partition/tiled.hpp"
#include "dem_test_util.hpp"
#include "heat_test_util.hpp"
#include "tiled_layouts.hpp"

namespace {

using demtest::Case;
const coloc::Comm kSelf(MPI_COMM_SELF);

/// Global sum over owned particles of f(store, i).
template <class F>
double globalSum(Case& c, F&& f) {
  double s = 0;
  for (std::size_t i = 0; i < c.p().nOwned; ++i) s += f(c.p(), i);
  return c.dec.comm().sum(s);
}

/// T by id over all ranks (n ids).
std::vector<double> temperatures(Case& c, long n) {
  return demtest::fieldById(c.p(), c.dec.comm(), n);
}

// r = 1 mm, spacing s = 2r - delta, delta = 10 um, L = 4 s; materials 0 (k 1, c_p 1) and 1
// (k 3, c_p 2): k_eff = 1.5 W/(m K).
constexpr double kR = 1e-3, kDelta = 1e-5, kS = 2 * kR - kDelta, kL = 4 * kS;

TEST(DemHeat, TwoBodyContactConductance) {
  const int P = coloc::Comm::world().size();
  // 1 and 2 ranks along x (the contacts straddle the rank face and the periodic face); more
  // ranks along y
  const coloc::Int3 dims = P <= 2 ? coloc::Int3{P, 1, 1} : coloc::Int3{1, P, 1};
  Case c(demtest::chainCase(), coloc::Comm::world(), dims);
  const double m = c.p().nOwned > 0 ? c.p().mass[0] : 0;
  const double mass = c.dec.comm().max(m);
  const double C1 = mass * 1, C2 = mass * 2;
  const double a = std::sqrt(0.5 * kR * kDelta);  // R* = r/2
  const double H = 2 * 1.5 * a;
  const double lambda = 2 * H * (1 / C1 + 1 / C2);  // two contacts per sphere
  const auto dT = [&] {
    const auto t = temperatures(c, 4);
    return 0.5 * (t[0] + t[1]) - 0.5 * (t[2] + t[3]);  // ids 0, 1: material 0 (hot)
  };
  const auto enthalpy = [&] {
    return globalSum(c, [&](const coloc::dem::ParticleStore& p, std::size_t i) {
      return p.mass[i] * (p.material[i] == 0 ? 1.0 : 2.0) * p.field("temperature")[i];
    });
  };
  const double dT0 = dT(), E0 = enthalpy();
  const int steps = 2000;
  for (int s = 0; s < steps; ++s) c.dem->substep();
  const double t = steps * c.dem->dt();
  const double rate = -std::log(dT() / dT0) / t;
  const double maxV = c.dec.comm().max([&] {
    double v = 0;
    for (std::size_t i = 0; i < c.p().nOwned; ++i)
      for (int d = 0; d < 3; ++d) v = std::max(v, std::fabs(c.p().v[d][i]));
    return v;
  }());
  const double dT1 = dT(), dE = std::fabs(enthalpy() - E0) / E0;
  const long long contacts = c.dec.comm().sum(c.dem->localContacts());
  if (c.dec.comm().isRoot())
    std::printf(
        "two-body, %d ranks: rate %.6e 1/s, analytic %.6e (rel %.2e); dT %.3f -> %.3f K; "
        "enthalpy rel change %.2e; max |v| %.2e m/s; contacts %lld\n",
        P, rate, lambda, std::fabs(rate / lambda - 1), dT0, dT1, dE, maxV, contacts);
  EXPECT_NEAR(rate / lambda, 1.0, 0.02);
  EXPECT_LT(dE, 1e-12);
  EXPECT_LT(maxV, 1e-6);  // static
}

TEST(DemHeat, SphereOnAWallRelaxesToItsTemperature) {
  // Hertz equilibrium overlap under gravity: 4/3 E* sqrt(r) delta^1.5 = m g (E* of particle
  // and wall material, both E = 1e7, nu = 0.3)
  const double E = 1e7, nu = 0.3, rho = 2500, g = 9.81;
  const double Estar = 1 / (2 * (1 - nu * nu) / E);
  const double m = rho * 4.0 / 3.0 * M_PI * kR * kR * kR;
  const double delta = std::pow(3 * m * g / (4 * Estar * std::sqrt(kR)), 2.0 / 3.0);
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"({
  "domain": {"length": [0.012, 0.012, 0.012], "cells": [12, 12, 12]},
  "gravity": [0, 0, -9.81],
  "particles": {
    "dt": 1e-5, "heat": true, "wall_temperature": 350, "wall_material": 1,
    "materials": [{"density": 2500, "young": 1e7, "heat_capacity": 0.1, "conductivity": 1},
                  {"density": 2500, "young": 1e7, "heat_capacity": 500, "conductivity": 4}],
    "sources": [{"type": "list", "material": 0, "radius": 0.001, "temperature": 300,
                 "positions": [0.006, 0.006, %.17g]}]
  }
})",
                kR - delta);
  Case c(buf);
  const double C = m * 0.1;
  const double keff = 2 * 1.0 * 4.0 / (1.0 + 4.0);
  const double H = 2 * keff * std::sqrt(kR * delta);
  const double lambda = H / C;
  const auto T = [&] { return temperatures(c, 1)[0]; };
  const double d0 = 350 - T();
  const int steps = 2000;
  const double E0 = globalSum(c, [](const coloc::dem::ParticleStore& p, std::size_t i) {
    return p.mass[i] * 0.1 * p.field("temperature")[i];
  });
  for (int s = 0; s < steps; ++s) c.dem->substep();
  const double rate = -std::log((350 - T()) / d0) / (steps * c.dem->dt());
  double z = c.p().nOwned > 0 ? c.p().x[2][0] : 0;
  z = c.dec.comm().sum(z);
  const auto diag = c.dem->diagnostics();
  const double E1 = diag["heat"]["enthalpy"].get<double>();
  const double W = diag["heat"]["wall_heat_in"].get<double>();
  const double T1 = T();
  if (c.dec.comm().isRoot())
    std::printf(
        "wall: rate %.6e 1/s, analytic %.6e (rel %.2e); overlap %.4e (Hertz %.4e); "
        "T %.3f K; enthalpy change - wall heat = %.2e relative\n",
        rate, lambda, std::fabs(rate / lambda - 1), kR - z, delta, T1, std::fabs(E1 - E0 - W) / E1);
  EXPECT_NEAR(rate / lambda, 1.0, 0.02);
  EXPECT_NEAR((kR - z) / delta, 1.0, 1e-3);
  EXPECT_LT(std::fabs(E1 - E0 - W) / E1, 1e-12);
}

using demtest::heatBed;  // the hot bed: 150 spheres, lower half 400 K, upper half 300 K
constexpr long kBedN = demtest::kHeatBedN;

TEST(DemHeat, ClosedBoxConservesEnthalpy) {
  for (const double wallT : {0.0, 350.0}) {
    Case c(heatBed(wallT));
    const double E0 = c.dem->diagnostics()["heat"]["enthalpy"].get<double>();
    for (int s = 0; s < 3000; ++s) c.dem->substep();
    const auto d = c.dem->diagnostics();
    const double E1 = d["heat"]["enthalpy"].get<double>();
    const double W = d["heat"]["wall_heat_in"].get<double>();
    const auto t = temperatures(c, kBedN);
    const double spread =
        *std::max_element(t.begin(), t.end()) - *std::min_element(t.begin(), t.end());
    if (c.dec.comm().isRoot())
      std::printf(
          "closed box, wall T %g K, %d ranks: |E1 - E0 - W|/E0 = %.2e, wall heat %.4e J "
          "(E0 %.4e J), contacts/particle %.2f, T spread %.3f K\n",
          wallT, c.dec.size(), std::fabs(E1 - E0 - W) / E0, W, E0,
          d["contacts_per_particle"].get<double>(), spread);
    EXPECT_LT(std::fabs(E1 - E0 - W) / E0, 1e-12);
    // the enthalpy at step 0 (the same sum, reduced alone: to the last bits)
    EXPECT_NEAR(d["heat"]["enthalpy_initial"].get<double>(), E0, 1e-15 * E0);
    EXPECT_LE(d["heat"]["energy_balance"].get<double>(), 1e-12);
    EXPECT_GT(d["contacts_per_particle"].get<double>(), 0.5);
    EXPECT_LT(spread, 99.0);  // heat moved between the halves
    if (wallT == 0)
      EXPECT_EQ(W, 0.0);
    else
      EXPECT_GT(std::fabs(W), 0.0);
  }
}

/// Largest |T_par - T_ser| / 100 K after `steps` sub-steps.
double bedAgainstSerial(Case& par, int steps) {
  Case ser(heatBed(350), kSelf, {1, 1, 1});
  for (int s = 0; s < steps; ++s) {
    par.dem->substep();
    ser.dem->substep();
  }
  const auto tp = temperatures(par, kBedN), ts = temperatures(ser, kBedN);
  double diff = 0;
  for (long k = 0; k < kBedN; ++k)
    diff = std::max(diff,
                    std::fabs(tp[static_cast<std::size_t>(k)] - ts[static_cast<std::size_t>(k)]));
  return diff / 100.0;
}

TEST(DemHeat, BedTemperaturesMatchSerial) {
  Case par(heatBed(350));
  const double d = bedAgainstSerial(par, 500);
  if (par.dec.comm().isRoot())
    std::printf("bed vs serial, %d ranks (grid %d x %d x %d): max |dT|/100 K = %.3e\n",
                par.dec.size(), par.dec.dims()[0], par.dec.dims()[1], par.dec.dims()[2], d);
  EXPECT_LT(d, 1e-10);
}

TEST(DemHeat, BedTemperaturesMatchSerialTiled) {
  const std::string text = heatBed(350);
  const coloc::GlobalGrid g = coloc::gridFromConfig(demtest::config(text));
  const coloc::Comm world = coloc::Comm::world();
  coloc::TiledOptions opt;
  opt.granularity = 2;
  const auto cost = coloc::test::heapedCost(g, {2, g.cells[1], 2}, 20.0);
  Case par(text,
           coloc::decompositionOf(world, coloc::tiledBoxes(g, cost, world.size(), opt).layout));
  const double d = bedAgainstSerial(par, 500);
  if (par.dec.comm().isRoot())
    std::printf("bed vs serial, %d ranks (tiled): max |dT|/100 K = %.3e\n", par.dec.size(), d);
  EXPECT_LT(d, 1e-10);
}

TEST(DemHeat, RestoreContinuesTemperaturesBitForBit) {
  Case a(heatBed(350));
  for (int s = 0; s < 200; ++s) a.dem->substep();
  coloc::dem::DemState st = a.dem->saveState();
  coloc::dem::DemSolver b(a.dec, a.cfg, a.timers, std::move(st));
  for (int s = 0; s < 200; ++s) {
    a.dem->substep();
    b.substep();
  }
  std::vector<double> ta(static_cast<std::size_t>(kBedN), 0.0), tb(ta);
  for (std::size_t i = 0; i < a.p().nOwned; ++i)
    ta[static_cast<std::size_t>(a.p().id[i])] = a.p().field("temperature")[i];
  for (std::size_t i = 0; i < b.particles().nOwned; ++i)
    tb[static_cast<std::size_t>(b.particles().id[i])] = b.particles().field("temperature")[i];
  a.dec.comm().sumInPlace(std::span<double>(ta));
  a.dec.comm().sumInPlace(std::span<double>(tb));
  long differ = 0;
  for (long k = 0; k < kBedN; ++k)
    differ += ta[static_cast<std::size_t>(k)] != tb[static_cast<std::size_t>(k)];
  EXPECT_EQ(differ, 0);
  // ... and the energy accounts: every rank continues its own shares
  const auto ha = a.dem->diagnostics()["heat"], hb = b.diagnostics()["heat"];
  for (const char* k : {"enthalpy", "enthalpy_initial", "wall_heat_in", "ext_heat_in",
                        "inflow_enthalpy_in", "outflow_enthalpy_out", "energy_balance"})
    EXPECT_EQ(hb[k].get<double>(), ha[k].get<double>()) << k;
  // a re-balance: the state restored onto a serial solver on rank 0 keeps every temperature
  coloc::dem::DemState st2 = b.saveState();
  std::vector<double> t2(static_cast<std::size_t>(kBedN), 0.0);
  const auto& T2 = st2.particles.field("temperature");
  for (std::size_t i = 0; i < st2.particles.nOwned; ++i)
    t2[static_cast<std::size_t>(st2.particles.id[i])] = T2[i];
  a.dec.comm().sumInPlace(std::span<double>(t2));
  long differ2 = 0;
  for (long k = 0; k < kBedN; ++k)
    differ2 += t2[static_cast<std::size_t>(k)] != tb[static_cast<std::size_t>(k)];
  EXPECT_EQ(differ2, 0);
}

TEST(DemHeat, RebalanceOntoTiledBoxesKeepsTemperatures) {
  // the state of a process-grid run restored onto tiled boxes (an in-memory re-balance): every
  // temperature arrives unchanged, and the two runs continue together to round-off
  const std::string text = heatBed(350);
  Case a(text);
  for (int s = 0; s < 200; ++s) a.dem->substep();
  const coloc::GlobalGrid g = coloc::gridFromConfig(a.cfg);
  coloc::TiledOptions opt;
  opt.granularity = 2;
  const auto cost = coloc::test::heapedCost(g, {2, g.cells[1], 2}, 20.0);
  const coloc::Decomposition boxes =
      coloc::decompositionOf(a.dec.comm(), coloc::tiledBoxes(g, cost, a.dec.size(), opt).layout);
  coloc::Timers timers;
  coloc::dem::DemSolver b(boxes, a.cfg, timers, a.dem->saveState());
  const auto tb = [&] {
    std::vector<double> t(static_cast<std::size_t>(kBedN), 0.0);
    const auto& T = b.particles().field("temperature");
    for (std::size_t i = 0; i < b.particles().nOwned; ++i)
      t[static_cast<std::size_t>(b.particles().id[i])] = T[i];
    a.dec.comm().sumInPlace(std::span<double>(t));
    return t;
  };
  EXPECT_EQ(tb(), temperatures(a, kBedN));
  for (int s = 0; s < 200; ++s) {
    a.dem->substep();
    b.substep();
  }
  const auto t1 = tb(), t0 = temperatures(a, kBedN);
  double d = 0;
  for (long k = 0; k < kBedN; ++k)
    d = std::max(d, std::fabs(t1[static_cast<std::size_t>(k)] - t0[static_cast<std::size_t>(k)]));
  if (a.dec.comm().isRoot())
    std::printf("re-balance onto tiled boxes, %d ranks: max |dT|/100 K after 200 steps %.3e\n",
                a.dec.size(), d / 100);
  EXPECT_LT(d / 100, 1e-10);
}

TEST(DemHeat, OffMeansNoFields) {
  const std::string on = heatBed(0);
  std::string off = on;
  off.replace(off.find("\"heat\": true"), 12, "\"heat\": false");
  Case c(off);
  EXPECT_TRUE(c.p().extra.empty());
  EXPECT_FALSE(c.dem->diagnostics().contains("heat"));
  Case h(on);
  EXPECT_EQ(coloc::dem::rowWidth(h.p(), coloc::dem::kOpGhostUpdate),
            coloc::dem::rowWidth(c.p(), coloc::dem::kOpGhostUpdate) + 1);
}

TEST(DemHeat, MaterialWithoutHeatCapacityIsRefused) {
  std::string text = heatBed(0);
  text.replace(text.find("\"heat_capacity\": 0.2, "), 22, "");
  try {
    Case c(text);
    FAIL() << "accepted";
  } catch (const coloc::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("particles.materials[0].heat_capacity"), std::string::npos)
        << e.what();
  }
}

}  // namespace
