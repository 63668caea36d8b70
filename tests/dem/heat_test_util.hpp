// Helpers of the particle heat tests (particles.heat; docs/heat.md, "Particles"): the hot-bed
// case, values of a per-particle field by id, and the energy accounts of the report.
#pragma once

#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "coloc/core/comm.hpp"
#include "coloc/dem/dem.hpp"

namespace demtest {

/// The periodic chain of the heat tests: four spheres of r = kChainR along x at spacing kChainS
/// (overlap kChainDelta with each neighbour, across the periodic face too), alternating
/// materials 0 (k 1, c_p 1; 400 K) and 1 (k 3, c_p 2; 300 K): k_eff = 1.5 W/(m K).
constexpr double kChainR = 1e-3, kChainDelta = 1e-5, kChainS = 2 * kChainR - kChainDelta;
inline std::string chainCase() {
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"({
  "domain": {"length": [%.17g, 0.012, 0.012], "cells": [4, 12, 12],
             "periodic": {"x": true, "y": false, "z": false}},
  "particles": {
    "dt": 1e-5, "heat": true,
    "materials": [{"density": 2500, "young": 1e7, "heat_capacity": 1, "conductivity": 1},
                  {"density": 2500, "young": 1e7, "heat_capacity": 2, "conductivity": 3}],
    "sources": [{"type": "list", "material": 0, "radius": 0.001, "temperature": 400,
                 "positions": [%.17g, 0.006, 0.006, %.17g, 0.006, 0.006]},
                {"type": "list", "material": 1, "radius": 0.001, "temperature": 300,
                 "positions": [%.17g, 0.006, 0.006, %.17g, 0.006, 0.006]}]
  }
})",
                4 * kChainS, 0.5 * kChainS, 2.5 * kChainS, 1.5 * kChainS, 3.5 * kChainS);
  return buf;
}

/// A box of 12 mm with a lattice of 5 x 5 x 6 spheres (r = 1 mm) slightly overlapping (spacing
/// 1.98 mm), under gravity: the lower three layers at 400 K, the upper three at 300 K; walls at
/// wallT (0: adiabatic, particles.wall_temperature left out). kHeatBedN particles, ids 0 ..
/// kHeatBedN - 1.
inline std::string heatBed(double wallT) {
  char wall[64] = "";
  if (wallT > 0) std::snprintf(wall, sizeof wall, R"( "wall_temperature": %.17g,)", wallT);
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"({
  "domain": {"length": [0.012, 0.012, 0.012], "cells": [6, 6, 6]},
  "gravity": [0, 0, -9.81],
  "particles": {
    "dt": 1e-5, "heat": true,%s
    "materials": [{"density": 2500, "young": 1e7, "restitution": 0.5,
                   "heat_capacity": 0.2, "conductivity": 2}],
    "sources": [{"type": "lattice", "lo": [0.00204, 0.00204, 0.00101], "counts": [5, 5, 3],
                 "spacing": [0.00198, 0.00198, 0.00198], "radius": 0.001, "temperature": 400},
                {"type": "lattice", "lo": [0.00204, 0.00204, 0.00695], "counts": [5, 5, 3],
                 "spacing": [0.00198, 0.00198, 0.00198], "radius": 0.001, "temperature": 300}]
  }
})",
                wall);
  return buf;
}
constexpr long kHeatBedN = 150;

/// The extra field `name` of the owned particles with ids 0 .. n-1, by id, over all ranks of
/// `comm` (0 for an id no rank holds). Collective.
inline std::vector<double> fieldById(const coloc::dem::ParticleStore& p, const coloc::Comm& comm,
                                     long n, const char* name = "temperature") {
  std::vector<double> t(static_cast<std::size_t>(n), 0.0);
  const auto& f = p.field(name);
  for (std::size_t i = 0; i < p.nOwned; ++i)
    if (p.id[i] >= 0 && p.id[i] < n) t[static_cast<std::size_t>(p.id[i])] = f[i];
  comm.sumInPlace(std::span<double>(t));
  return t;
}

}  // namespace demtest
