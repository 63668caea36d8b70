// Writing a checkpoint must not change the run, and a restart must be the uninterrupted run
// (issue 27): for every partition strategy, on any rank count (CTest runs 1-7), at steps where
// particles have crossed block faces since the last neighbour rebuild and touch particles of
// other blocks and periodic images:
//   the run that writes checkpoints at several steps  == the run that writes none   (bitwise)
//   a restart from each of those checkpoints           == the run that writes none   (bitwise)
//   a restart on other blocks (another strategy)       == to round-off (1e-10 relative)
//   an in-memory re-balance onto the same blocks      == bitwise
//   an in-memory re-balance onto other blocks and back  == to round-off
// The cases: a dense granular gas with random velocities in a box periodic along x and y
// (DEM only: many crossings and contacts each step), and a small fluidised bed (coupled: the
// fluid's history terms and the drag forces held over the sub-steps are part of the state), also
// heated (fluid and particle temperatures, the heat rates held over the sub-steps, Gunn
// convection, conduction through contacts and the walls).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "coloc/coupling/checkpoint.hpp"
#include "coloc/coupling/simulation.hpp"

using namespace coloc;
namespace fs = std::filesystem;

namespace {

// 6 x 5 x 15 cells (no rank count of 2-7 divides all of them), periodic along x and y.
const char* kGas = R"({
  "name": "ck-gas",
  "domain": { "length": [0.012, 0.01, 0.03], "cells": [6, 5, 15], "periodic": {"x": true, "y": true} },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "steps": 12, "mode": "particles" },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 2e-4 },
  "particles": { "dt": 2e-5, "skin": 0.6,
    "materials": [ { "density": 2500.0, "young": 5e5, "poisson": 0.3, "restitution": 0.8,
                     "friction": 0.4 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.0], "hi": [0.012, 0.01, 0.03],
                   "count": 1000, "radius": 0.0005, "velocity": [0.1, -0.05, 0.0],
                   "velocity_spread": 0.3 } ] },
  "coupling": { "dem_substeps": 10 }
})";

// A fluidised bed: inlet below, outlet above, periodic along x.
const char* kBed = R"({
  "name": "ck-bed",
  "domain": { "length": [0.012, 0.01, 0.03], "cells": [6, 5, 15], "periodic": {"x": true} },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "steps": 10 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 5e-4, "initial_velocity": [0, 0, 0.05],
             "boundary": { "zlo": { "type": "inlet", "velocity": [0, 0, 0.05],
                                    "superficial": true },
                           "zhi": { "type": "outlet", "pressure": 0.0 } },
             "pressure": { "tol": 1e-12 } },
  "particles": { "dt": 5e-5, "skin": 0.5,
    "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3, "restitution": 0.8,
                     "friction": 0.4 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.001], "hi": [0.012, 0.01, 0.014],
                   "count": 400, "radius": 0.0005, "velocity_spread": 0.1 } ] },
  "coupling": { "drag": "difelice", "kernel": "trilinear", "dem_substeps": 10 }
})";

// The bed heated: a hot inflow into a cooler bed, hot walls for the particles.
const char* kHeatedBed = R"({
  "name": "ck-heated-bed",
  "domain": { "length": [0.012, 0.01, 0.03], "cells": [6, 5, 15], "periodic": {"x": true} },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "steps": 10 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 5e-4, "initial_velocity": [0, 0, 0.05],
             "heat": true, "conductivity": 0.6, "heat_capacity": 4186.0,
             "initial_temperature": 300.0,
             "boundary": { "zlo": { "type": "inlet", "velocity": [0, 0, 0.05],
                                    "superficial": true, "temperature": 350.0 },
                           "zhi": { "type": "outlet", "pressure": 0.0 } },
             "pressure": { "tol": 1e-12 } },
  "particles": { "dt": 5e-5, "skin": 0.5, "heat": true, "wall_temperature": 330.0,
    "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3, "restitution": 0.8,
                     "friction": 0.4, "heat_capacity": 800.0, "conductivity": 1.0 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.001], "hi": [0.012, 0.01, 0.014],
                   "count": 400, "radius": 0.0005, "velocity_spread": 0.1,
                   "temperature": 310.0 } ] },
  "coupling": { "drag": "difelice", "kernel": "trilinear", "dem_substeps": 10,
                "heat_transfer": "gunn" }
})";

Config config(const char* text, std::vector<std::string> overrides = {}) {
  return Config::fromText(text, "test", std::move(overrides), coupling::caseSchema());
}

std::string scratchDir() {
  const Comm w = Comm::world();
  std::string d;
  if (w.isRoot()) {
    std::string tmpl = (fs::temp_directory_path() / "coloc_ckinv_XXXXXX").string();
    if (char* p = mkdtemp(tmpl.data())) d = p;
  }
  return w.broadcast(d);
}

/// Everything the next step reads, by particle id and global cell (sums over the ranks): x, v,
/// omega, f, torque, f_ext of every particle (with heat also its temperature and held heat
/// rate); p, eps and the cell-centred u of every cell (with heat also T).
std::vector<double> state(coupling::Simulation& sim, long long nParticles) {
  const auto& p = sim.particles()->particles();
  const bool heat = std::any_of(p.extra.begin(), p.extra.end(),
                                [](const auto& e) { return e.name == "temperature"; });
  const int kRow = heat ? 20 : 18, kCell = heat ? 6 : 5;
  const auto& dec = sim.decomposition();
  const auto& g = dec.grid();
  const bool fluid = sim.fluid() != nullptr;
  const long long cells = fluid ? g.cellCount() : 0;
  std::vector<double> out(static_cast<std::size_t>(kRow * nParticles + kCell * cells), 0.0);
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    double* o = &out[static_cast<std::size_t>(kRow * p.id[i])];
    for (const auto* a : {&p.x, &p.v, &p.omega, &p.f, &p.torque, &p.fExt}) {
      for (int d = 0; d < 3; ++d) o[d] = (*a)[d][i];
      o += 3;
    }
    if (heat) {
      o[0] = p.field("temperature")[i];
      o[1] = p.field("heat_ext")[i];
    }
  }
  if (fluid) {
    const auto& f = std::as_const(*sim.fluid()).fields();
    std::array<CellField, 3> u;
    for (auto& c : u) c = CellField(f.p.layout());
    sim.fluid()->cellVelocity(u);
    forEach(f.p.interior(), [&](int i, int j, int k) {
      const long long c =
          dec.lo()[0] + i + g.cells[0] * (dec.lo()[1] + j + g.cells[1] * (dec.lo()[2] + k));
      double* o = &out[static_cast<std::size_t>(kRow * nParticles + kCell * c)];
      o[0] = f.p(i, j, k);
      o[1] = f.eps(i, j, k);
      for (int d = 0; d < 3; ++d) o[2 + d] = u[static_cast<std::size_t>(d)](i, j, k);
      if (heat) o[5] = f.T(i, j, k);
    });
  }
  dec.comm().sumInPlace(std::span<double>(out));
  return out;
}

/// Particles now owned by a rank other than the owner of their position: those that crossed a
/// block face (or a periodic face) since the last neighbour rebuild (global count).
long long crossed(coupling::Simulation& sim) {
  const auto& dec = sim.particleDecomposition();
  const auto& g = dec.grid();
  const auto& p = sim.particles()->particles();
  long long n = 0;
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    Int3 cell{};
    for (int d = 0; d < 3; ++d) {
      double x = p.x[d][i];
      if (g.periodic[d]) x -= g.length[d] * std::floor((x - g.origin[d]) / g.length[d]);
      const double h = g.length[d] / g.cells[d];
      cell[d] = std::clamp(static_cast<int>(std::floor((x - g.origin[d]) / h)), 0, g.cells[d] - 1);
    }
    if (dec.ownerOfCell(cell) != dec.rank()) ++n;
  }
  return dec.comm().sum(n);
}

void expectBitwise(const std::vector<double>& ref, const std::vector<double>& got,
                   const std::string& what) {
  ASSERT_EQ(ref.size(), got.size()) << what;
  std::size_t differ = 0, first = ref.size();
  for (std::size_t i = 0; i < ref.size(); ++i)
    if (ref[i] != got[i] && !(std::isnan(ref[i]) && std::isnan(got[i]))) {
      if (differ++ == 0) first = i;
    }
  EXPECT_EQ(differ, 0u) << what << ": " << differ << " values differ, the first at entry " << first
                        << " (" << (first < ref.size() ? ref[first] : 0.0) << " vs "
                        << (first < ref.size() ? got[first] : 0.0) << ")";
}

void expectRoundOff(const std::vector<double>& ref, const std::vector<double>& got,
                    const std::string& what) {
  ASSERT_EQ(ref.size(), got.size()) << what;
  double scale = 0, worst = 0;
  for (double v : ref) scale = std::max(scale, std::fabs(v));
  for (std::size_t i = 0; i < ref.size(); ++i) worst = std::max(worst, std::fabs(got[i] - ref[i]));
  EXPECT_LE(worst, 1e-10 * scale) << what;
}

/// The whole matrix for one case and strategy.
void checkInvariance(const char* text, const std::string& strategy, const std::string& other) {
  const Comm world = Comm::world();
  const Config cfg = config(text, {"partition.strategy=" + strategy});
  const std::string dir = scratchDir();
  const auto pathAt = [&](long long s) {
    return (fs::path(dir) / ("ck" + std::to_string(s) + ".h5")).string();
  };

  // the run that writes nothing
  coupling::Simulation a(world, cfg);
  const long long n = a.particles()->globalCount();
  while (!a.finished()) a.step();
  const auto ref = state(a, n);

  // The same run writing checkpoints: on several ranks at the first three steps where
  // particles have crossed block faces since the last rebuild (the state a checkpoint used to
  // lose), on one rank at steps 3, 4 and 7; one more in-memory save (re-balancing's) besides.
  std::vector<long long> at;
  long long crossings = 0;
  {
    coupling::Simulation b(world, cfg);
    while (!b.finished()) {
      b.step();
      const long long c = crossed(b);
      const bool due =
          world.size() > 1 ? c > 0 : (b.steps() == 3 || b.steps() == 4 || b.steps() == 7);
      if (!due || at.size() == 3 || b.finished()) continue;
      crossings += c;
      at.push_back(b.steps());
      b.writeCheckpoint(pathAt(b.steps()));
      (void)b.particles()->saveState();
    }
    expectBitwise(ref, state(b, n), strategy + ": the run that wrote checkpoints");
  }
  // the matrix means something only where particles had crossed faces at the checkpoints
  ASSERT_FALSE(at.empty()) << strategy << ": no checkpoint written";
  if (world.size() > 1) {
    EXPECT_GE(at.size(), 2u) << strategy << ": fewer than two steps with crossings";
  }
  if (world.isRoot()) {
    std::printf("[ %s ] %d ranks: checkpoints at steps", strategy.c_str(), world.size());
    for (long long s : at) std::printf(" %lld", s);
    std::printf(" (%lld particles had crossed a face since the last rebuild)\n", crossings);
  }
  std::vector<std::string> paths;
  for (long long s : at) paths.push_back(pathAt(s));

  // restarts on the blocks that wrote them: bitwise
  for (std::size_t k = 0; k < at.size(); ++k) {
    coupling::Simulation c(cfg, coupling::Simulation::restartLayouts(world, cfg, paths[k]),
                           paths[k]);
    EXPECT_EQ(c.steps(), at[k]);
    while (!c.finished()) c.step();
    EXPECT_EQ(c.demSubsteps(), a.demSubsteps());
    expectBitwise(ref, state(c, n), strategy + ": restart from step " + std::to_string(at[k]));
  }

  // a restart with another strategy (other blocks): round-off
  {
    const Config cfgO = config(text, {"partition.strategy=" + other});
    coupling::Simulation d(cfgO, coupling::Simulation::restartLayouts(world, cfgO, paths[0]),
                           paths[0]);
    while (!d.finished()) d.step();
    expectRoundOff(ref, state(d, n), strategy + " -> " + other + " restart");
  }

  // re-balancing in memory at step 4 onto the same blocks: bitwise
  {
    coupling::Simulation e(world, cfg);
    while (e.steps() < 4) e.step();
    coupling::Simulation f(cfg, coupling::Simulation::chooseLayouts(world, cfg), e);
    while (!f.finished()) f.step();
    expectBitwise(ref, state(f, n), strategy + ": re-balanced in memory onto the same blocks");
  }

  // re-balancing in memory at step 4 onto the other strategy's blocks and back at step 7
  {
    const Config cfgO = config(text, {"partition.strategy=" + other});
    coupling::Simulation e(world, cfg);
    while (e.steps() < 4) e.step();
    coupling::Simulation f(cfgO, coupling::Simulation::chooseLayouts(world, cfgO), e);
    while (f.steps() < 7) f.step();
    coupling::Simulation h(cfg, coupling::Simulation::chooseLayouts(world, cfg), f);
    while (!h.finished()) h.step();
    expectRoundOff(ref, state(h, n), strategy + " re-balanced to " + other + " and back");
  }
  world.barrier();
  if (world.isRoot()) fs::remove_all(dir);
}

TEST(CheckpointInvariance, GranularGasUniform) {
  checkInvariance(kGas, "uniform", "tiled");
}
TEST(CheckpointInvariance, GranularGasBalanced) {
  checkInvariance(kGas, "balanced", "uniform");
}
TEST(CheckpointInvariance, GranularGasTiled) {
  checkInvariance(kGas, "tiled", "balanced");
}
TEST(CheckpointInvariance, FluidisedBedBalanced) {
  checkInvariance(kBed, "balanced", "tiled");
}
TEST(CheckpointInvariance, FluidisedBedTiled) {
  checkInvariance(kBed, "tiled", "uniform");
}
TEST(CheckpointInvariance, FluidisedBedIndependent) {
  checkInvariance(kBed, "independent", "uniform");
}
TEST(CheckpointInvariance, HeatedBedTiled) {
  checkInvariance(kHeatedBed, "tiled", "independent");
}

}  // namespace
