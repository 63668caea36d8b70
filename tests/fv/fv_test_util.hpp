// Helpers of the fluid validation tests: a case from JSON text, global reductions over owned
// cells and faces.
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/fv/fluid.hpp"
#include "coloc/partition/setup.hpp"

namespace fvtest {

inline coloc::Schema schema() {
  coloc::Schema s;
  coloc::declareRunConfig(s);
  coloc::declareDomainConfig(s);
  coloc::fv::declareConfig(s);
  return s;
}

inline coloc::Config config(const std::string& json,
                            const std::vector<std::string>& overrides = {}) {
  return coloc::Config::fromText(json, "test", overrides, schema());
}

/// The open channel of the parallel and heat tests, fluid only: a box of 1.3 x 0.9 x 0.7 m on
/// 13 x 9 x 7 cells (blocks that do not divide evenly), periodic along z, gravity -1 m/s^2 along
/// y, an inlet on xlo at (1, 0.1, 0.05) m/s, an outlet on xhi, a wall on ylo, a lid moving at
/// (0.3, 0, 0.2) m/s on yhi. `fluid`: more keys of "fluid" (each followed by a comma);
/// `pressure`: the keys of fluid.pressure; `inlet`, `wall`: more keys of the inlet and of the ylo
/// wall (each after a comma).
inline std::string channelCase(const std::string& fluid, const std::string& pressure,
                               const std::string& inlet = "", const std::string& wall = "") {
  return R"({
  "run": {"mode": "fluid"},
  "gravity": [0.0, -1.0, 0.0],
  "domain": {"length": [1.3, 0.9, 0.7], "cells": [13, 9, 7], "periodic": {"z": true}},
  "fluid": {"nu": 0.01, )" +
         fluid + R"("adaptive_dt": true, "dt": 0.05, "cfl": 0.4, "pressure": {)" + pressure +
         R"(},
            "boundary": {"xlo": {"type": "inlet", "velocity": [1.0, 0.1, 0.05])" +
         inlet + R"(},
                         "xhi": {"type": "outlet"},
                         "ylo": {"type": "wall")" +
         wall + R"(},
                         "yhi": {"type": "wall", "velocity": [0.3, 0.0, 0.2]}}}
})";
}

/// The channel with fluid.heat (rho 2, k 0.05, c_p 3, T0 320 K; the inlet at 350 K, the ylo wall
/// at 300 K, the lid adiabatic); `tol`: the pressure tolerance (fluid.pressure.tol).
inline std::string heatChannelCase(const std::string& tol) {
  return channelCase(R"("rho": 2.0, "heat": true, "conductivity": 0.05, "heat_capacity": 3.0, )"
                     R"("initial_temperature": 320.0, )",
                     R"("tol": )" + tol + R"(, "max_iter": 400)", R"(, "temperature": 350.0)",
                     R"(, "temperature": 300.0)");
}

/// The channel's fluid fraction at x and time t (0.6 .. 0.95, moving).
inline double channelEps(const coloc::Real3& x, double t) {
  return 0.75 + 0.15 * std::sin(4.0 * x[0] - 3.0 * t) * std::cos(3.0 * x[1]) +
         0.05 * std::cos(2 * M_PI * x[2] / 0.7);
}

/// Owned faces of component d: [0,n) plus face n at a non-periodic high box face.
inline coloc::IndexBox ownedFaces(const coloc::Decomposition& dec, int d) {
  return coloc::faceOwned(dec, d);
}

/// Physical position of local face (i,j,k) of component d.
inline coloc::Real3 facePos(const coloc::Decomposition& dec, int d, int i, int j, int k) {
  const auto& g = dec.grid();
  const int idx[3] = {i, j, k};
  coloc::Real3 x;
  for (int a = 0; a < 3; ++a)
    x[a] = g.origin[a] + (dec.lo()[a] + idx[a] + (a == d ? 0.0 : 0.5)) * g.spacing(a);
  return x;
}

inline coloc::Real3 cellPos(const coloc::Decomposition& dec, int i, int j, int k) {
  return facePos(dec, -1, i, j, k);
}

/// ||(eps^{n+1}-eps^n)/dt + div(eps_f u)||_2 over all cells (u's ghosts on the block's high
/// faces current: call cellVelocity() first).
inline double continuityNorm(const coloc::Decomposition& dec, const coloc::fv::FluidFields& f,
                             const coloc::CellField& epsN, double dt) {
  double s2 = 0;
  const auto& g = dec.grid();
  coloc::forEach(coloc::IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    double div = 0;
    for (int a = 0; a < 3; ++a) {
      const int di = a == 0, dj = a == 1, dk = a == 2;
      const double elo = 0.5 * (f.eps(i, j, k) + f.eps(i - di, j - dj, k - dk));
      const double ehi = 0.5 * (f.eps(i, j, k) + f.eps(i + di, j + dj, k + dk));
      div += (ehi * f.u[a](i + di, j + dj, k + dk) - elo * f.u[a](i, j, k)) / g.spacing(a);
    }
    const double c = (f.eps(i, j, k) - epsN(i, j, k)) / dt + div;
    s2 += c * c;
  });
  return std::sqrt(dec.comm().sum(s2));
}

/// Run until the steady residual drops below `tol` or `maxSteps` are done; returns the steps.
inline long long runSteady(coloc::fv::FluidSolver& s, double tol, long long maxSteps) {
  long long n = 0;
  for (; n < maxSteps; ++n) {
    s.step(s.nextDt());
    if (n > 10 && s.diagnostics()["fluid"]["steady_residual"].get<double>() < tol) break;
  }
  return n + 1;
}

}  // namespace fvtest
