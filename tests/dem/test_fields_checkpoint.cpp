// The particle field table reaches checkpoint files: a DemState with extra fields (one table
// entry each) written by writeDemState and read back by readDemState (an even split of the rows,
// not the writer's) restores a solver whose particles carry their values; a file without extra
// fields has none.
#include <gtest/gtest.h>

#include "checkpoint_test_util.hpp"
#include "dem_test_util.hpp"

namespace {

using coloc::dem::kOpGhostBuild;
using coloc::dem::kOpMigrate;
using coloc::dem::kOpState;

const char* kBox = R"({
  "gravity": [0, 0, -9.81],
  "domain": {"length": [0.04, 0.04, 0.04], "cells": [8, 8, 8], "periodic": {"x": true}},
  "particles": {
    "dt": 1e-5,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.7,
                   "friction": 0.5}],
    "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.04, 0.04, 0.04], "count": 1500,
                 "radius": 0.001, "gap": 0.02, "velocity": [0.5, 0, 0], "velocity_spread": 0.3}]
  }
})";

long wrong(const coloc::dem::ParticleStore& p) {
  long bad = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.field("tag")[i] != 2.0 * static_cast<double>(p.id[i]) + 1) ++bad;
    for (int k = 0; k < 3; ++k)
      if (p.field("dir", k)[i] != (i < p.nOwned ? static_cast<double>(k - p.id[i]) : 0.0)) ++bad;
  }
  return bad;
}

TEST(ParticleFields, CheckpointFile) {
  demtest::Case a(kBox);
  const auto& comm = a.dec.comm();
  auto& p = a.p();
  p.addField("tag", 1, kOpGhostBuild | kOpMigrate | kOpState);
  p.addField("dir", 3, kOpMigrate | kOpState);
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    p.field("tag")[i] = 2.0 * static_cast<double>(p.id[i]) + 1;
    for (int k = 0; k < 3; ++k) p.field("dir", k)[i] = static_cast<double>(k - p.id[i]);
  }
  for (int s = 0; s < 50; ++s) a.dem->substep();
  coloc::dem::DemState st = demtest::throughFile(comm, "fields", a.dem->saveState());
  ASSERT_EQ(st.particles.extra.size(), 2u);
  EXPECT_EQ(st.particles.extra[1].name, "dir");
  EXPECT_EQ(st.particles.extra[1].components, 3);
  coloc::dem::DemSolver b(a.dec, a.cfg, a.timers, std::move(st));
  EXPECT_EQ(b.globalCount(), 1500);
  EXPECT_EQ(comm.sum(wrong(b.particles())), 0);
  EXPECT_GT(comm.sum(static_cast<long>(b.particles().nGhost)), 0);
  for (int s = 0; s < 50; ++s) b.substep();
  EXPECT_EQ(comm.sum(wrong(b.particles())), 0);
}

}  // namespace
