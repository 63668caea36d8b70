// The library path of checkpoint/restart that re-balancing uses: write a checkpoint, construct a
// Simulation from it on given blocks. The same blocks continue bitwise; other cuts (uneven, as a
// balancer would choose) agree to round-off. The particles come from the file, not the case.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "coloc/core/error.hpp"
#include "coloc/coupling/checkpoint.hpp"
#include "coloc/coupling/simulation.hpp"

using namespace coloc;
namespace fs = std::filesystem;

namespace {

const char* kCase = R"({
  "name": "ck-layouts",
  "domain": { "length": [0.01, 0.01, 0.04], "cells": [4, 4, 16] },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "steps": 8 },
  "partition": { "dims": [1, 1, 0] },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 1e-3, "initial_velocity": [0, 0, 0.05],
             "boundary": { "zlo": { "type": "inlet", "velocity": [0, 0, 0.05],
                                    "superficial": true },
                           "zhi": { "type": "outlet", "pressure": 0.0 } },
             "pressure": { "tol": 1e-12 } },
  "particles": { "dt": 5e-5,
    "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3, "restitution": 0.9,
                     "friction": 0.3 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.001], "hi": [0.01, 0.01, 0.015],
                   "count": 300, "radius": 0.0005 } ] },
  "coupling": { "drag": "difelice", "kernel": "trilinear" }
})";

Config config(std::vector<std::string> overrides = {}) {
  return Config::fromText(kCase, "test", overrides, coupling::caseSchema());
}

std::string scratch(const std::string& name) {
  const Comm w = Comm::world();
  std::string d;
  if (w.isRoot()) {
    std::string tmpl = (fs::temp_directory_path() / "coloc_rl_XXXXXX").string();
    if (char* p = mkdtemp(tmpl.data())) d = p;
  }
  return (fs::path(w.broadcast(d)) / name).string();
}

/// Particle positions and velocities by id, and the pressure by global cell (sums over ranks).
std::vector<double> state(coupling::Simulation& sim, long long nParticles) {
  const auto& dec = sim.decomposition();
  const auto& g = dec.grid();
  std::vector<double> out(static_cast<std::size_t>(6 * nParticles + g.cellCount()), 0.0);
  const auto& p = sim.particles()->particles();
  for (std::size_t i = 0; i < p.nOwned; ++i)
    for (int d = 0; d < 3; ++d) {
      out[static_cast<std::size_t>(6 * p.id[i] + d)] = p.x[d][i];
      out[static_cast<std::size_t>(6 * p.id[i] + 3 + d)] = p.v[d][i];
    }
  const auto& pf = std::as_const(*sim.fluid()).fields().p;
  forEach(pf.interior(), [&](int i, int j, int k) {
    const long long c =
        dec.lo()[0] + i + g.cells[0] * (dec.lo()[1] + j + g.cells[1] * (dec.lo()[2] + k));
    out[static_cast<std::size_t>(6 * nParticles + c)] = pf(i, j, k);
  });
  dec.comm().sumInPlace(std::span<double>(out));
  return out;
}

TEST(RestartLayouts, SameBlocksBitwiseOtherCutsToRoundOff) {
  const Config cfg = config();
  const Comm world = Comm::world();
  const std::string path = scratch("ck.h5");
  coupling::Layouts layouts = coupling::Simulation::chooseLayouts(world, cfg);
  coupling::Simulation a(cfg, layouts);
  const long long n = a.particles()->globalCount();
  for (int s = 0; s < 4; ++s) a.step();
  a.writeCheckpoint(path);
  while (!a.finished()) a.step();
  const auto ref = state(a, n);

  coupling::Simulation b(cfg, layouts, path);
  EXPECT_EQ(b.steps(), 4);
  EXPECT_EQ(b.particles()->globalCount(), n);
  while (!b.finished()) b.step();
  EXPECT_EQ(b.steps(), a.steps());
  EXPECT_EQ(b.time(), a.time());
  EXPECT_EQ(b.demSubsteps(), a.demSubsteps());
  const auto same = state(b, n);
  for (std::size_t i = 0; i < ref.size(); ++i) ASSERT_EQ(same[i], ref[i]) << "entry " << i;

  // Uneven cuts along z (what a balancer might choose): to round-off.
  const auto& g = layouts.fluid.grid();
  std::array<std::vector<int>, 3> cuts{std::vector<int>{0, 4}, std::vector<int>{0, 4},
                                       std::vector<int>{0}};
  const int p = world.size();
  for (int r = 1; r < p; ++r) cuts[2].push_back(16 * r / p + (r == 1 ? -3 : 0));
  cuts[2].push_back(16);
  coupling::Layouts other{
      Decomposition::fromCuts(world, g, cuts), std::nullopt, "uniform", CostModel{}, 1.0, 1.0};
  coupling::Simulation c(cfg, other, path);
  while (!c.finished()) c.step();
  const auto oth = state(c, n);
  double scale = 0;
  for (double v : ref) scale = std::max(scale, std::fabs(v));
  double worst = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) worst = std::max(worst, std::fabs(oth[i] - ref[i]));
  EXPECT_LE(worst, 1e-10 * scale);

  // A checkpoint of another grid is refused on every rank, with the reason.
  const Config bigger = config({"domain.cells=[4,4,20]"});
  try {
    coupling::Simulation d(bigger, coupling::Simulation::chooseLayouts(world, bigger), path);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("its grid has 4x4x16 cells"), std::string::npos)
        << e.what();
  }
  world.barrier();
  if (world.isRoot()) fs::remove_all(fs::path(path).parent_path());
}

TEST(RestartLayouts, TiledBoxesFromTheCheckpointContinueBitwise) {
  // The tiled strategy: the checkpoint records every rank's box; a restart on as many ranks
  // rebuilds those boxes (restartLayouts), so the continuation is bitwise; a restart on the
  // uniform blocks agrees to round-off.
  const Config cfg = config({"partition.strategy=tiled", "partition.dims=[0,0,0]"});
  const Comm world = Comm::world();
  const std::string path = scratch("ck-tiled.h5");
  coupling::Simulation a(world, cfg);
  ASSERT_TRUE(a.decomposition().isTiled());
  const long long n = a.particles()->globalCount();
  for (int s = 0; s < 4; ++s) a.step();
  a.writeCheckpoint(path);
  const auto info = coupling::readCheckpointInfo(world, path);
  EXPECT_EQ(info.strategy, "tiled");
  ASSERT_EQ(info.fluidBoxLo.size(), static_cast<std::size_t>(world.size()));
  for (int r = 0; r < world.size(); ++r) {
    EXPECT_EQ(info.fluidBoxLo[static_cast<std::size_t>(r)], a.decomposition().loOf(r));
    EXPECT_EQ(info.fluidBoxHi[static_cast<std::size_t>(r)], a.decomposition().hiOf(r));
  }
  while (!a.finished()) a.step();
  const auto ref = state(a, n);

  coupling::Simulation b(cfg, coupling::Simulation::restartLayouts(world, cfg, path), path);
  ASSERT_TRUE(b.decomposition().isTiled());
  while (!b.finished()) b.step();
  const auto same = state(b, n);
  for (std::size_t i = 0; i < ref.size(); ++i) ASSERT_EQ(same[i], ref[i]) << "entry " << i;

  const Config uniform = config({"partition.dims=[0,0,0]"});
  coupling::Simulation c(uniform, coupling::Simulation::restartLayouts(world, uniform, path), path);
  EXPECT_FALSE(c.decomposition().isTiled());
  while (!c.finished()) c.step();
  const auto oth = state(c, n);
  double scale = 0, worst = 0;
  for (double v : ref) scale = std::max(scale, std::fabs(v));
  for (std::size_t i = 0; i < ref.size(); ++i) worst = std::max(worst, std::fabs(oth[i] - ref[i]));
  EXPECT_LE(worst, 1e-10 * scale);
  world.barrier();
  if (world.isRoot()) fs::remove_all(fs::path(path).parent_path());
}

}  // namespace
