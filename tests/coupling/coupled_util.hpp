// Helpers for the coupled validation tests: build a case from JSON text, track one particle.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "coloc/coupling/simulation.hpp"

namespace coloc::test {

inline Config caseFromText(const std::string& text, std::vector<std::string> overrides = {}) {
  return Config::fromText(text, "test", overrides, coupling::caseSchema());
}

/// Position, velocity and external force of the particle with global id `id` (collective).
struct ParticleState {
  std::array<double, 3> x{}, v{}, f{};
  bool found = false;
};

inline ParticleState particleState(coupling::Simulation& sim, std::int64_t id) {
  double buf[10] = {0};
  const auto& p = sim.particles()->particles();
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    if (p.id[i] != id) continue;
    for (int d = 0; d < 3; ++d) {
      buf[d] = p.x[d][i];
      buf[3 + d] = p.v[d][i];
      buf[6 + d] = p.fExt[d][i];
    }
    buf[9] = 1.0;
  }
  sim.decomposition().comm().sumInPlace(std::span<double>(buf, 10));
  ParticleState s;
  for (int d = 0; d < 3; ++d) {
    s.x[d] = buf[d];
    s.v[d] = buf[3 + d];
    s.f[d] = buf[6 + d];
  }
  s.found = buf[9] == 1.0;
  return s;
}

/// The re-balancing tests' case: `count` spheres settling in the lower quarter of a tall closed
/// box with an outlet on top (even blocks cut it along z: the upper blocks hold no particles),
/// balanced blocks; `partition` adds keys to the partition object (e.g. a re-balance interval).
inline std::string settlingBedCase(int count, int steps, const std::string& partition = "") {
  return R"({
  "domain": { "length": [0.06, 0.04, 0.12], "cells": [6, 4, 12] },
  "gravity": [0.0, 0.0, -9.81],
  "partition": { "strategy": "balanced")" +
         (partition.empty() ? "" : ", " + partition) + R"( },
  "run": { "steps": )" +
         std::to_string(steps) + R"( },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 2e-3,
             "boundary": { "zhi": { "type": "outlet", "pressure": 0.0 } },
             "pressure": { "tol": 1e-13 } },
  "particles": { "dt": 5e-5,
    "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3, "friction": 0.5 } ],
    "sources": [ { "type": "random", "lo": [0.002, 0.002, 0.002], "hi": [0.058, 0.038, 0.03],
                   "count": )" +
         std::to_string(count) + R"(, "radius": 0.0014, "velocity_spread": 0.05 } ] },
  "coupling": { "drag": "difelice" }
})";
}

/// The same process grid with every interior cut one cell lower where the blocks allow it (a
/// re-balance target that moves cells and particles between every pair of neighbours).
inline coupling::Layouts shiftedLayouts(const Decomposition& dec) {
  auto cuts = dec.cuts();
  for (auto& c : cuts)
    for (std::size_t b = 1; b + 1 < c.size(); ++b)
      if (c[b] - 1 - c[b - 1] >= 2) c[b] -= 1;
  return {Decomposition::fromCuts(dec.comm(), dec.grid(), cuts),
          std::nullopt,
          "balanced",
          CostModel{},
          1.0,
          1.0};
}

/// The Ergun bed tests' measurement: the mean pressure (kinematic) and fluid fraction of each
/// global x-layer of cells (`cellsPerLayer` cells each), and over layers i0..i1 the
/// least-squares slope of the pressure (1/m, times rho for Pa/m) and the mean fraction.
struct LayerGradient {
  double slope = 0, eps = 0;
};
inline LayerGradient layerGradient(coupling::Simulation& sim, int i0, int i1,
                                   double cellsPerLayer) {
  const auto& dec = sim.decomposition();
  const auto& f = sim.fluid()->fields();
  const int nx = dec.grid().cells[0];
  const double h = dec.grid().spacing(0);
  std::vector<double> layer(2 * static_cast<std::size_t>(nx), 0.0);
  forEach(f.p.interior(), [&](int i, int j, int k) {
    layer[static_cast<std::size_t>(dec.lo()[0] + i)] += f.p(i, j, k) / cellsPerLayer;
    layer[static_cast<std::size_t>(nx + dec.lo()[0] + i)] += f.eps(i, j, k) / cellsPerLayer;
  });
  dec.comm().sumInPlace(std::span<double>(layer));
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  LayerGradient g;
  const int n = i1 - i0 + 1;
  for (int i = i0; i <= i1; ++i) {
    const double x = (i + 0.5) * h, y = layer[static_cast<std::size_t>(i)];
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    g.eps += layer[static_cast<std::size_t>(nx + i)] / n;
  }
  g.slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  return g;
}

/// The planner tests' bed: a layered bed in a closed box, gas from below (coupled, DEM ghosts
/// every sub-step).
inline const char* const kLayeredBedCase = R"({
  "domain": { "length": [0.16, 0.04, 0.16], "cells": [16, 4, 16] },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "mode": "coupled", "steps": 1 },
  "fluid": { "nu": 1.5e-5, "rho": 1.2, "dt": 5e-4,
             "boundary": { "zlo": { "type": "inlet", "velocity": [0.0, 0.0, 0.3], "superficial": true },
                           "zhi": { "type": "outlet", "pressure": 0.0 } } },
  "particles": {
    "dt": 5e-5,
    "materials": [ { "density": 2500.0, "young": 1e6, "poisson": 0.3 } ],
    "sources": [ { "type": "layered", "lo": [0.0, 0.0, 0.0], "hi": [0.16, 0.04, 0.05],
                   "count": 1500, "radius": 0.002 } ]
  }
})";

/// The planner tests' periodic box: particles spread through a box periodic along x, coupled
/// (DEM ghosts cross the periodic face with a shift).
inline const char* const kPeriodicSuspensionCase = R"({
  "domain": { "length": [0.16, 0.04, 0.12], "cells": [16, 4, 12], "periodic": { "x": true } },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "mode": "coupled", "steps": 1 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 5e-4, "initial_velocity": [0.02, 0.0, 0.0] },
  "particles": {
    "dt": 5e-5,
    "materials": [ { "density": 2500.0, "young": 1e6, "poisson": 0.3 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.0], "hi": [0.16, 0.04, 0.12],
                   "count": 900, "radius": 0.002, "velocity_spread": 0.0 } ]
  }
})";

/// This rank alone, for the serial reference run beside a parallel one (freed at scope end:
/// declare it before the simulations that use it).
class SelfComm {
 public:
  SelfComm() { MPI_Comm_split(MPI_COMM_WORLD, Comm::world().rank(), 0, &raw_); }
  ~SelfComm() { MPI_Comm_free(&raw_); }
  SelfComm(const SelfComm&) = delete;
  SelfComm& operator=(const SelfComm&) = delete;
  Comm comm() const { return Comm(raw_); }

 private:
  MPI_Comm raw_ = MPI_COMM_NULL;
};

/// A cell field's owned values by global cell (x fastest), the same on every rank (collective).
inline std::vector<double> globalCellValues(coupling::Simulation& sim, const Field3<double>& f) {
  const auto& dec = sim.decomposition();
  const auto g = dec.grid();
  std::vector<double> out(static_cast<std::size_t>(g.cellCount()), 0.0);
  forEach(f.interior(), [&](int i, int j, int k) {
    const long long gi = dec.lo()[0] + i, gj = dec.lo()[1] + j, gk = dec.lo()[2] + k;
    out[static_cast<std::size_t>(gi + g.cells[0] * (gj + g.cells[1] * gk))] = f(i, j, k);
  });
  dec.comm().sumInPlace(std::span<double>(out));
  return out;
}

}  // namespace coloc::test
