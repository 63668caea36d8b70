// Terminal settling velocity of one sphere in still fluid (two-way coupled, gravity on both
// phases, buoyancy through -V_p grad p).
//  - Stokes drag, Re ~ 1e-3: v_t = (rho_p - rho_f) g d^2 / (18 mu) within 1 %.
//  - Di Felice drag at Re ~ 10: v_t within 2 % of the root of
//    (rho_p - rho_f) g V_p = beta_DiFelice(eps = 1, v_t) v_t.
// Cells are 100 diameters wide so that the particle's own disturbance of the fluid (unresolved
// CFD-DEM) stays well below the tolerance. The sphere is alone, so its material is soft (E = 1 kPa)
// only to keep the DEM time-step check (a fraction of the Rayleigh time) out of the way.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "coloc/coupling/drag.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

std::string settlingCase(double d, double rhoP, double h, double dtFluid, double dtDem,
                         const char* drag, double endTime) {
  const double lx = 16 * h, lz = 24 * h;
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"({
    "domain": { "length": [%.17g, %.17g, %.17g], "cells": [16, 16, 24] },
    "gravity": [0.0, 0.0, -9.81],
    "run": { "steps": 0, "end_time": %.17g },
    "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": %.17g,
               "boundary": { "zhi": { "type": "outlet", "pressure": 0.0 } },
               "pressure": { "tol": 1e-12 } },
    "particles": { "dt": %.17g, "bin_cells": 1,
      "materials": [ { "density": %.17g, "young": 1e3, "poisson": 0.3, "restitution": 0.9 } ],
      "sources": [ { "type": "list", "positions": [%.17g, %.17g, %.17g], "radius": %.17g } ] },
    "coupling": { "drag": "%s", "kernel": "trilinear" }
  })",
                lx, lx, lz, endTime, dtFluid, dtDem, rhoP, 0.5 * lx + 0.3 * h, 0.5 * lx + 0.2 * h,
                0.7 * lz, 0.5 * d, drag);
  return buf;
}

double settle(const std::string& text) {
  const Config cfg = test::caseFromText(text);
  coupling::Simulation sim(Comm::world(), cfg);
  while (!sim.finished()) sim.step();
  const auto s = test::particleState(sim, 0);
  EXPECT_TRUE(s.found);
  EXPECT_LT(std::abs(s.v[0]), 1e-3 * std::abs(s.v[2]));
  return -s.v[2];
}

}  // namespace

TEST(Settling, StokesTerminalVelocity) {
  const double d = 4e-5, rhoP = 2500.0, mu = 1e-3;
  const double vt = (rhoP - 1000.0) * 9.81 * d * d / (18.0 * mu);  // 1.31e-3 m/s
  const double tau = rhoP * d * d / (18.0 * mu);                   // 2.2e-4 s
  ASSERT_LT(1000.0 * vt * d / mu, 0.1);                            // Re = 0.05
  const double v = settle(settlingCase(d, rhoP, 100 * d, tau / 8, tau / 160, "stokes", 25 * tau));
  std::printf("Stokes settling: v = %.6e m/s, Stokes law %.6e m/s, ratio %.5f\n", v, vt, v / vt);
  EXPECT_NEAR(v / vt, 1.0, 0.01) << "v = " << v << ", Stokes " << vt;
}

TEST(Settling, DiFeliceTerminalVelocityAtReTen) {
  const double d = 1e-3, nu = 1e-6, rhoF = 1000.0, g = 9.81;
  const double vp = std::numbers::pi * d * d * d / 6.0;
  // Particle density chosen so that the terminal Reynolds number is 10.
  const double vTarget = 10.0 * nu / d;
  const double rhoP =
      rhoF + coupling::dragCoefficient(coupling::DragLaw::DiFelice, 1.0, d, vTarget, rhoF, nu) *
                 vTarget / (g * vp);
  // Reference: the root of the force balance, by bisection.
  auto balance = [&](double v) {
    return (rhoP - rhoF) * g * vp -
           coupling::dragCoefficient(coupling::DragLaw::DiFelice, 1.0, d, v, rhoF, nu) * v;
  };
  double lo = 1e-6, hi = 1.0;
  for (int it = 0; it < 200; ++it) (balance(0.5 * (lo + hi)) > 0 ? lo : hi) = 0.5 * (lo + hi);
  const double vt = 0.5 * (lo + hi);
  const double tau =
      rhoP * vp / coupling::dragCoefficient(coupling::DragLaw::DiFelice, 1.0, d, vt, rhoF, nu);
  const double v =
      settle(settlingCase(d, rhoP, 100 * d, tau / 10, tau / 200, "difelice", 12 * tau));
  std::printf("Di Felice settling: v = %.6e m/s, force balance %.6e m/s, ratio %.5f, Re %.2f\n", v,
              vt, v / vt, vt * d / nu);
  EXPECT_NEAR(v / vt, 1.0, 0.02) << "v = " << v << ", force balance " << vt << ", Re "
                                 << vt * d / nu;
}
