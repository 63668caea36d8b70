// Checkpoint of the fluid solver alone: write the state after a few steps (changing eps, K, KUp,
// AB2, adaptive dt), restore it into a fresh solver and continue. Same decomposition: bitwise
// identical to the uninterrupted run. Another decomposition of the same ranks: equal to round-off.
// A file of another grid, a missing file and a non-checkpoint file: coloc::Error on every rank.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/coupling/checkpoint.hpp"
#include "coloc/partition/setup.hpp"

using namespace coloc;
namespace fs = std::filesystem;

namespace {

const char* kCase = R"({
  "name": "ck-fluid",
  "domain": { "origin": [0, 0, 0], "length": [1.2, 0.6, 0.4], "cells": [12, 6, 4] },
  "run": { "mode": "fluid" },
  "fluid": {
    "nu": 0.01, "initial_velocity": [0.5, 0.0, 0.0],
    "boundary": { "xlo": { "type": "inlet", "velocity": [0.5, 0.0, 0.0] },
                  "xhi": { "type": "outlet", "pressure": 0.0 } },
    "dt": 0.02, "adaptive_dt": true, "cfl": 0.4, "time_scheme": "ab2",
    "pressure": { "tol": 1e-12 }
  }
})";

Config config(const std::vector<std::string>& overrides = {}) {
  Schema s;
  declareRunConfig(s);
  declareDomainConfig(s);
  fv::declareConfig(s);
  return Config::fromText(kCase, "test", overrides, s);
}

/// fluid.heat on: a hot inlet into a cooler fluid, a wall at a fixed temperature (docs/heat.md).
const std::vector<std::string> kHeat = {
    "fluid.heat=true",
    "fluid.conductivity=0.02",
    "fluid.heat_capacity=2.0",
    "fluid.initial_temperature=300",
    R"(fluid.boundary.xlo={"type": "inlet", "velocity": [0.5, 0.0, 0.0], "temperature": 350})",
    R"(fluid.boundary.ylo={"type": "wall", "temperature": 280})"};

std::string scratchFile(const std::string& name) {
  const Comm w = Comm::world();
  std::string d;
  if (w.isRoot()) {
    std::string tmpl = (fs::temp_directory_path() / "coloc_ckf_XXXXXX").string();
    if (char* p = mkdtemp(tmpl.data())) d = p;
  }
  return (fs::path(w.broadcast(d)) / name).string();
}

/// Coefficients that change every step, as the coupling's would.
void setCoefficients(const Decomposition& dec, fv::FluidSolver& s, int k) {
  auto& f = s.edit();
  const auto& g = dec.grid();
  forEach(f.p.interior(), [&](int i, int j, int kk) {
    const double x = g.origin[0] + (dec.lo()[0] + i + 0.5) * g.spacing(0);
    const double y = g.origin[1] + (dec.lo()[1] + j + 0.5) * g.spacing(1);
    const double z = g.origin[2] + (dec.lo()[2] + kk + 0.5) * g.spacing(2);
    f.eps(i, j, kk) = 1.0 - 0.3 * std::exp(-20 * ((x - 0.5 - 0.02 * k) * (x - 0.5 - 0.02 * k) +
                                                  (y - 0.3) * (y - 0.3) + (z - 0.2) * (z - 0.2)));
    f.K(i, j, kk) = 5.0 * (1.0 - f.eps(i, j, kk));
    f.KUp[0](i, j, kk) = 0.1 * f.K(i, j, kk);
    f.KUp[1](i, j, kk) = 0.0;
    f.KUp[2](i, j, kk) = -0.05 * f.K(i, j, kk);
  });
}

void advance(const Decomposition& dec, fv::FluidSolver& s, int from, int count) {
  for (int k = from; k < from + count; ++k) {
    setCoefficients(dec, s, k);
    s.step(s.nextDt());
  }
}

/// Owned cells of p and the cell-centred velocity, as global arrays (sum over ranks).
std::vector<double> global(const Decomposition& dec, fv::FluidSolver& s) {
  std::array<CellField, 3> uc;
  s.cellVelocity(uc);
  const auto& g = dec.grid();
  std::vector<double> out(static_cast<std::size_t>(4 * g.cellCount()), 0.0);
  const auto& p = s.fields().p;
  forEach(p.interior(), [&](int i, int j, int k) {
    const long long gi = dec.lo()[0] + i, gj = dec.lo()[1] + j, gk = dec.lo()[2] + k;
    const std::size_t c = static_cast<std::size_t>(gi + g.cells[0] * (gj + g.cells[1] * gk));
    out[4 * c] = p(i, j, k);
    for (int d = 0; d < 3; ++d) out[4 * c + 1 + static_cast<std::size_t>(d)] = uc[d](i, j, k);
  });
  dec.comm().sumInPlace(std::span<double>(out));
  return out;
}

void writeCheckpoint(const std::string& path, const Decomposition& dec, const fv::FluidSolver& s) {
  H5File f = H5File::create(dec.comm(), path, true);
  coupling::writeFluidState(f, "/fluid", dec, s);
  f.close();
}

TEST(CheckpointFluid, RestoreContinuesBitwiseAndOnOtherBlocks) {
  const Config cfg = config();
  const Comm world = Comm::world();
  const Decomposition dec = decompositionFromConfig(world, cfg);
  const std::string path = scratchFile("fluid.h5");
  Timers t1, t2, t3;
  fv::FluidSolver a(dec, cfg, t1);
  a.syncEpsOld();
  advance(dec, a, 0, 4);
  writeCheckpoint(path, dec, a);
  const fv::FluidCounters ca = a.counters();
  advance(dec, a, 4, 4);
  const auto ref = global(dec, a);
  const double refDt = a.nextDt();

  // Same blocks: bitwise.
  fv::FluidSolver b(dec, cfg, t2);
  {
    H5File f = H5File::openRead(world, path);
    coupling::readFluidState(f, "/fluid", dec, b);
  }
  EXPECT_EQ(b.counters().steps, ca.steps);
  EXPECT_EQ(b.time(), ca.time);
  advance(dec, b, 4, 4);
  const auto got = global(dec, b);
  ASSERT_EQ(got.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) ASSERT_EQ(got[i], ref[i]) << "entry " << i;
  EXPECT_EQ(b.time(), a.time());
  EXPECT_EQ(b.nextDt(), refDt);
  EXPECT_EQ(b.counters().itSum, a.counters().itSum);

  // Other blocks (x and y swapped in the process grid): equal to round-off.
  const Int3 d0 = dec.dims();
  const Decomposition other = Decomposition::uniform(world, dec.grid(), {d0[1], d0[0], d0[2]});
  fv::FluidSolver c(other, cfg, t3);
  {
    H5File f = H5File::openRead(world, path);
    coupling::readFluidState(f, "/fluid", other, c);
  }
  advance(other, c, 4, 4);
  const auto oth = global(other, c);
  double scale = 0;
  for (double v : ref) scale = std::max(scale, std::fabs(v));
  for (std::size_t i = 0; i < ref.size(); ++i)
    ASSERT_LE(std::fabs(oth[i] - ref[i]), 1e-10 * scale) << "entry " << i;
  EXPECT_NEAR(c.time(), a.time(), 1e-12 * a.time());
  world.barrier();
  if (world.isRoot()) fs::remove_all(fs::path(path).parent_path());
}

TEST(CheckpointFluid, RestoreContinuesTheTemperatureBitwise) {
  // fluid.heat: T and the energy accounting through the checkpoint, same blocks: bitwise.
  const Config cfg = config(kHeat);
  const Comm world = Comm::world();
  const Decomposition dec = decompositionFromConfig(world, cfg);
  const std::string path = scratchFile("fluid-heat.h5");
  Timers t1, t2;
  fv::FluidSolver a(dec, cfg, t1);
  a.syncEpsOld();
  advance(dec, a, 0, 4);
  writeCheckpoint(path, dec, a);
  advance(dec, a, 4, 4);
  fv::FluidSolver b(dec, cfg, t2);
  {
    H5File f = H5File::openRead(world, path);
    coupling::readFluidState(f, "/fluid", dec, b);
  }
  advance(dec, b, 4, 4);
  const auto& Ta = a.fields().T;
  const auto& Tb = b.fields().T;
  long long differ = 0;
  forEach(Ta.interior(), [&](int i, int j, int k) { differ += Ta(i, j, k) != Tb(i, j, k); });
  EXPECT_EQ(world.sum(differ), 0);
  const Json da = a.diagnostics(), db = b.diagnostics();
  EXPECT_EQ(da["fluid_heat"].dump(), db["fluid_heat"].dump());
  EXPECT_LE(db["checks"]["fluid_energy_balance"].get<double>(), 1e-12);
  world.barrier();
  if (world.isRoot()) fs::remove_all(fs::path(path).parent_path());
}

TEST(CheckpointFluid, BadFilesGiveAnErrorOnEveryRank) {
  const Comm world = Comm::world();
  const std::string dir = fs::path(scratchFile("x")).parent_path().string();
  // missing
  EXPECT_THROW(coupling::readCheckpointInfo(world, dir + "/missing.h5"), Error);
  // not HDF5
  if (world.isRoot()) std::ofstream(dir + "/garbage.h5") << "this is not an HDF5 file\n";
  world.barrier();
  try {
    coupling::readCheckpointInfo(world, dir + "/garbage.h5");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("garbage.h5"), std::string::npos) << e.what();
  }
  // HDF5 but not a checkpoint
  {
    H5File f = H5File::create(world, dir + "/plain.h5");
    f.setAttribute("/", "time", 1.0);
    f.close();
  }
  try {
    coupling::readCheckpointInfo(world, dir + "/plain.h5");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a coloc checkpoint"), std::string::npos) << e.what();
  }
  world.barrier();
  if (world.isRoot()) fs::remove_all(dir);
}

}  // namespace
