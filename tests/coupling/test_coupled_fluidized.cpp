// A fluidised bed above minimum fluidisation: 1500 glass spheres (d = 1 mm, rho_p = 2500) in
// water, in a column periodic across the flow (no wall friction), superficial inlet velocity
// (the bed rests on the inlet) at the bottom at
// U = 0.03 m/s (about 3.7 U_mf; U_mf = 8.0e-3 m/s from Wen & Yu's correlation, the terminal
// velocity is about 0.15 m/s). Once fluidised, the mean dynamic pressure drop across the column,
//     dP = rho_f (p_inlet - p_outlet) - rho_f g H
// between the inlet plane (p extrapolated linearly from the first two cell layers) and the
// outlet plane (p = 0 there) of a column of height H,
// equals the buoyant weight of the bed per area, (rho_p - rho_f) g N V_p / A, within 3 %.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "coupled_util.hpp"

using namespace coloc;

namespace {
const char* kCase = R"({
  "domain": { "length": [0.01, 0.01, 0.1], "cells": [4, 4, 40],
              "periodic": { "x": true, "y": true } },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "steps": 0, "end_time": 0.5 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 1e-3, "initial_velocity": [0, 0, 0.03],
             "boundary": { "zlo": { "type": "inlet", "velocity": [0, 0, 0.03],
                                     "superficial": true },
                           "zhi": { "type": "outlet", "pressure": 0.0 } },
             "pressure": { "tol": 1e-10 } },
  "particles": { "dt": 5e-5,
    "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3, "restitution": 0.9,
                     "friction": 0.3 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.001], "hi": [0.01, 0.01, 0.03],
                   "count": 1500, "radius": 0.0005 } ] },
  "coupling": { "drag": "difelice", "kernel": "trilinear" }
})";
}  // namespace

TEST(FluidisedBed, PressureDropEqualsBuoyantWeight) {
  const Config cfg = test::caseFromText(kCase);
  coupling::Simulation sim(Comm::world(), cfg);
  const auto& dec = sim.decomposition();
  const int nz = dec.grid().cells[2];
  const double h = dec.grid().spacing(2), area = 0.01 * 0.01, g = 9.81, rhoF = 1000.0;
  const double weight = (2500.0 - rhoF) * g * 1500 * std::numbers::pi * 1e-9 / 6.0 / area;
  double sum = 0;
  int samples = 0;
  double bedTop = 0;
  while (!sim.finished()) {
    sim.step();
    if (sim.time() < 0.3) continue;  // fluidisation transient
    std::vector<double> layer(2, 0.0);
    const auto& p = sim.fluid()->fields().p;
    forEach(p.interior(), [&](int i, int j, int k) {
      const int gk = dec.lo()[2] + k;
      if (gk < 2) layer[static_cast<std::size_t>(gk)] += p(i, j, k) / 16.0;
    });
    dec.comm().sumInPlace(std::span<double>(layer));
    const double pInlet = 1.5 * layer[0] - 0.5 * layer[1];
    sum += rhoF * (pInlet - 0.0) - rhoF * g * nz * h;
    ++samples;
  }
  const auto& parts = sim.particles()->particles();
  for (std::size_t i = 0; i < parts.nOwned; ++i) bedTop = std::max(bedTop, parts.x[2][i]);
  bedTop = dec.comm().max(bedTop);
  const double dp = sum / samples;
  if (dec.comm().isRoot())
    std::printf(
        "fluidised bed: mean dP %.3f Pa, buoyant weight / area %.3f Pa, ratio %.4f, "
        "highest particle at %.1f mm\n",
        dp, weight, dp / weight, 1e3 * bedTop);
  EXPECT_EQ(sim.particles()->globalCount(), 1500);
  EXPECT_LT(bedTop, 0.095);  // the bed stays in the column
  EXPECT_NEAR(dp / weight, 1.0, 0.03);
}
