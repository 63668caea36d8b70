// Particle temperatures (particles.heat) through a checkpoint file: a bed with a hot half run
// 200 sub-steps, its state written by writeDemState and read back by readDemState (an even split
// of the rows, not the writer's); the restored solver continues the temperatures bit for bit
// against the run that wrote it, 200 sub-steps on (docs/heat.md, "Particles").
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "coloc/coupling/checkpoint.hpp"
#include "coloc/io/h5io.hpp"
#include "dem_test_util.hpp"

namespace {

const char* kBed = R"({
  "domain": {"length": [0.012, 0.012, 0.012], "cells": [6, 6, 6]},
  "gravity": [0, 0, -9.81],
  "particles": {
    "dt": 1e-5, "heat": true, "wall_temperature": 350,
    "materials": [{"density": 2500, "young": 1e7, "restitution": 0.5,
                   "heat_capacity": 0.2, "conductivity": 2}],
    "sources": [{"type": "lattice", "lo": [0.00204, 0.00204, 0.00101], "counts": [5, 5, 3],
                 "spacing": [0.00198, 0.00198, 0.00198], "radius": 0.001, "temperature": 400},
                {"type": "lattice", "lo": [0.00204, 0.00204, 0.00695], "counts": [5, 5, 3],
                 "spacing": [0.00198, 0.00198, 0.00198], "radius": 0.001, "temperature": 300}]
  }
})";
constexpr long kN = 150;

std::vector<double> temperatures(const coloc::dem::ParticleStore& p, const coloc::Comm& comm) {
  std::vector<double> t(static_cast<std::size_t>(kN), 0.0);
  const auto& T = p.field("temperature");
  for (std::size_t i = 0; i < p.nOwned; ++i) t[static_cast<std::size_t>(p.id[i])] = T[i];
  comm.sumInPlace(std::span<double>(t));
  return t;
}

TEST(DemHeat, CheckpointFileContinuesTemperatures) {
  demtest::Case a(kBed);
  const auto& comm = a.dec.comm();
  for (int s = 0; s < 200; ++s) a.dem->substep();
  const std::string path =
      (std::filesystem::temp_directory_path() /
       ("coloc_heat_" + std::to_string(comm.size()) + "_" + std::to_string(::getpid()) + ".h5"))
          .string();
  const std::string file = comm.broadcast(path);
  {
    coloc::H5File f = coloc::H5File::create(comm, file);
    coloc::coupling::writeDemState(f, "/particles", a.dem->saveState());
    f.close();
  }
  coloc::H5File f = coloc::H5File::openRead(comm, file);
  coloc::dem::DemState st = coloc::coupling::readDemState(f, "/particles");
  f.close();
  coloc::dem::DemSolver b(a.dec, a.cfg, a.timers, std::move(st));
  EXPECT_EQ(temperatures(b.particles(), comm), temperatures(a.p(), comm));
  for (int s = 0; s < 200; ++s) {
    a.dem->substep();
    b.substep();
  }
  const auto ta = temperatures(a.p(), comm), tb = temperatures(b.particles(), comm);
  long differ = 0;
  double spread = 0;
  for (long k = 0; k < kN; ++k) {
    differ += ta[static_cast<std::size_t>(k)] != tb[static_cast<std::size_t>(k)];
    spread = std::max(spread, std::fabs(ta[static_cast<std::size_t>(k)] - 350.0));
  }
  if (comm.isRoot())
    std::printf("checkpoint file, %d ranks: %ld of %ld temperatures differ after 200 steps\n",
                comm.size(), differ, kN);
  EXPECT_EQ(differ, 0);
  EXPECT_GT(spread, 1.0);  // not trivially equal
  comm.barrier();
  if (comm.isRoot()) std::remove(file.c_str());
}

}  // namespace
