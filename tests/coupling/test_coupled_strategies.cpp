// Partition strategies on the same physics: uniform (co-located), balanced (co-located, cuts
// from the cost model), independent (the DEM on its own blocks, every fluid-particle transfer
// by MPI) and tiled (co-located, one general box per rank by recursive bisection of the cost
// model). Each run on this communicator (1-7 ranks; a strategy with a process grid is skipped
// where the grid cannot hold one, as at 7 ranks) is compared with a serial run of the same
// case (a settling bed in a closed box, and a suspension periodic along x whose particles cross
// the periodic face): every particle's position and velocity equal to 1e-10 relative after the run;
// particle count conserved; the independent mode books its coupling traffic as inter-physics
// remote. The heated bed adds heat (fluid energy, particle temperature, conduction through
// contacts and the hot walls, Gunn convection): temperatures equal to 1e-12 relative, the heat the
// particles receive equal to the heat the fluid loses to round-off in every step.
#include <algorithm>
#include <map>

#include "coupled_util.hpp"

using namespace coloc;

namespace {

// Particles settle in a closed box with an outlet on top, in the lower half only (so the
// balanced and independent layouts differ from the uniform one).
const char* kCase = R"({
  "domain": { "length": [0.06, 0.04, 0.08], "cells": [6, 5, 8] },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "steps": 40 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 2e-3,
             "boundary": { "zhi": { "type": "outlet", "pressure": 0.0 } },
             "pressure": { "tol": 1e-13 } },
  "particles": { "dt": 5e-5,
    "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3 } ],
    "sources": [ { "type": "random", "lo": [0.002, 0.002, 0.002], "hi": [0.058, 0.038, 0.03],
                   "count": 150, "radius": 0.0012, "velocity_spread": 0.02 } ] },
  "coupling": { "drag": "difelice" }
})";

// The bed heated: hot floor (fluid) and walls (particles), warm particles in cooler water.
const char* kHeatedCase = R"({
  "domain": { "length": [0.06, 0.04, 0.08], "cells": [6, 5, 8] },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "steps": 40 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 2e-3,
             "heat": true, "conductivity": 0.6, "heat_capacity": 4186.0,
             "initial_temperature": 300.0,
             "boundary": { "zhi": { "type": "outlet", "pressure": 0.0 },
                           "zlo": { "type": "wall", "temperature": 360.0 } },
             "pressure": { "tol": 1e-13 } },
  "particles": { "dt": 5e-5, "heat": true, "wall_temperature": 340.0,
    "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3,
                     "heat_capacity": 800.0, "conductivity": 1.0 } ],
    "sources": [ { "type": "random", "lo": [0.002, 0.002, 0.002], "hi": [0.058, 0.038, 0.03],
                   "count": 150, "radius": 0.0012, "velocity_spread": 0.02,
                   "temperature": 320.0 } ] },
  "coupling": { "drag": "difelice", "heat_transfer": "gunn" }
})";

struct Snapshot {
  std::vector<double> x, v, T;
  long long count = 0;
};

Snapshot snapshot(coupling::Simulation& sim, int n) {
  Snapshot s;
  s.x.assign(3 * static_cast<std::size_t>(n), 0.0);
  s.v.assign(3 * static_cast<std::size_t>(n), 0.0);
  const auto& p = sim.particles()->particles();
  for (std::size_t i = 0; i < p.nOwned; ++i)
    for (int d = 0; d < 3; ++d) {
      s.x[3 * static_cast<std::size_t>(p.id[i]) + static_cast<std::size_t>(d)] = p.x[d][i];
      s.v[3 * static_cast<std::size_t>(p.id[i]) + static_cast<std::size_t>(d)] = p.v[d][i];
    }
  const bool heat = std::any_of(p.extra.begin(), p.extra.end(),
                                [](const auto& e) { return e.name == "temperature"; });
  if (heat) {
    s.T.assign(static_cast<std::size_t>(n), 0.0);
    const auto& T = p.field("temperature");
    for (std::size_t i = 0; i < p.nOwned; ++i) s.T[static_cast<std::size_t>(p.id[i])] = T[i];
  }
  const auto& comm = sim.decomposition().comm();
  comm.sumInPlace(std::span<double>(s.x));
  comm.sumInPlace(std::span<double>(s.v));
  comm.sumInPlace(std::span<double>(s.T));
  s.count = sim.particles()->globalCount();
  return s;
}

struct Param {
  const char* name;
  const char* text;
  const char* steps;  // run.steps
  std::string strategy;
};

void PrintTo(const Param& p, std::ostream* os) {
  *os << p.name << " case, " << p.strategy;
}

class Strategy : public ::testing::TestWithParam<Param> {};

}  // namespace

TEST_P(Strategy, SameTrajectoriesAsSerial) {
  const Comm world = Comm::world();
  const test::SelfComm selfComm;
  const Param& P = GetParam();
  {
    const Config cfg = test::caseFromText(
        P.text, {"partition.strategy=" + P.strategy, std::string("run.steps=") + P.steps});
    const Config serialCfg = test::caseFromText(P.text, {std::string("run.steps=") + P.steps});
    std::unique_ptr<coupling::Simulation> made;
    try {
      made = std::make_unique<coupling::Simulation>(world, cfg);
    } catch (const ConfigError& e) {
      if (P.strategy == "tiled" ||
          std::string(e.what()).find("partition.dims") == std::string::npos)
        throw;
      GTEST_SKIP() << "no process grid of " << world.size() << " ranks: " << e.what();
    }
    coupling::Simulation& par = *made;
    coupling::Simulation ser(selfComm.comm(), serialCfg);
    while (!par.finished()) {
      par.step();
      ser.step();
    }
    const int n = static_cast<int>(ser.particles()->globalCount());
    const auto& len = par.decomposition().grid().length;
    const double L = std::max({len[0], len[1], len[2]});
    const auto a = snapshot(par, n), b = snapshot(ser, n);
    EXPECT_EQ(a.count, n);
    double vmax = 0;
    for (double v : b.v) vmax = std::max(vmax, std::abs(v));
    ASSERT_GT(vmax, 0.0);
    for (std::size_t k = 0; k < a.x.size(); ++k) {
      ASSERT_NEAR(a.x[k], b.x[k], 1e-10 * L) << "particle " << k / 3;
      ASSERT_NEAR(a.v[k], b.v[k], 1e-10 * vmax) << "particle " << k / 3;
    }
    EXPECT_LE(par.momentumBalance(), 1e-12);
    ASSERT_EQ(a.T.size(), b.T.size());
    if (!b.T.empty()) {
      // The temperatures moved (convection and conduction), the same as in the serial run.
      double spread = 0;
      for (std::size_t k = 0; k < b.T.size(); ++k) {
        spread = std::max(spread, std::abs(b.T[k] - 320.0));
        ASSERT_NEAR(a.T[k], b.T[k], 1e-12 * b.T[k]) << "particle " << k;
      }
      EXPECT_GT(spread, 1e-3);
      EXPECT_LE(par.heatBalance(), 1e-12);
      const auto& Ta = par.fluid()->fields().T;
      const auto& Tb = ser.fluid()->fields().T;
      const Int3 lo = par.decomposition().lo();
      forEach(Ta.interior(), [&](int i, int j, int k) {
        ASSERT_NEAR(Ta(i, j, k), Tb(lo[0] + i, lo[1] + j, lo[2] + k), 1e-12 * Tb(0, 0, 0));
      });
    }
    const Json r = par.report(1.0);
    EXPECT_EQ(r["partition"]["strategy"].get<std::string>(), P.strategy);
    if (!b.T.empty()) {
      EXPECT_LE(r["checks"]["heat_exchange_balance"].get<double>(), 1e-12);
      EXPECT_LE(r["checks"]["energy_balance"].get<double>(), 1e-12);
    }
    if (P.strategy == "independent") {
      EXPECT_TRUE(par.independent());
      if (world.size() > 1) {
        EXPECT_GT(r["exchange"]["inter_physics_remote"]["bytes"].get<long long>(), 0);
        // The bed fills the lower half: the DEM's blocks balanced by count differ from the
        // fluid's (a uniform suspension may keep the same grid).
        if (std::string(P.name) == "bed") {
          EXPECT_NE(par.particleDecomposition().dims(), par.decomposition().dims());
        }
      }
    } else {
      EXPECT_FALSE(par.independent());
    }
    // every strategy reports every rank's block; they tile the grid (cells add up)
    ASSERT_EQ(r["partition"]["boxes"].size(), static_cast<std::size_t>(world.size()));
    long long cells = 0;
    for (const auto& b : r["partition"]["boxes"])
      cells += (b[3].get<long long>() - b[0].get<long long>()) *
               (b[4].get<long long>() - b[1].get<long long>()) *
               (b[5].get<long long>() - b[2].get<long long>());
    const auto& g = par.decomposition().grid();
    EXPECT_EQ(cells, static_cast<long long>(g.cells[0]) * g.cells[1] * g.cells[2]);
    EXPECT_EQ(r["partition"].contains("particle_boxes"), par.independent());
    if (P.strategy == "tiled") {
      EXPECT_TRUE(par.decomposition().isTiled());
      EXPECT_TRUE(r["partition"]["fluid_dims"].is_null());
    }
  }
}

std::vector<Param> params() {
  std::vector<Param> out;
  for (const char* st : {"uniform", "balanced", "independent", "tiled"}) {
    out.push_back({"bed", kCase, "40", st});
    out.push_back({"periodic", test::kPeriodicSuspensionCase, "6", st});
    out.push_back({"heated", kHeatedCase, "20", st});
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(Strategies, Strategy, ::testing::ValuesIn(params()), [](const auto& info) {
  return std::string(info.param.name) + "_" + info.param.strategy;
});
