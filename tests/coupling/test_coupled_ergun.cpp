// A fixed bed (DummyDEM: particles frozen, every exchange done) of a simple cubic lattice with
// fluid fraction 0.40, periodic across the flow, Gidaspow drag (Ergun branch): the steady
// pressure gradient in the bed interior is within 5 % of the Ergun equation
//   -dP/dx = 150 mu (1-eps)^2 U / (eps^3 d^2) + 1.75 rho (1-eps) U^2 / (eps^3 d)
// at three superficial velocities U (particle Reynolds numbers about 2, 10 and 50).
#include <cmath>
#include <cstdio>
#include <numbers>

#include "coupled_util.hpp"

using namespace coloc;

namespace {

constexpr double kD = 1.0465e-3;  // diameter: 64 spheres per 4 mm cell give eps = 0.3999
constexpr double kMu = 1e-3, kRho = 1000.0;

std::string bedCase(double u) {
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"({
    "domain": { "length": [0.12, 0.016, 0.016], "cells": [30, 4, 4],
                "periodic": { "y": true, "z": true } },
    "run": { "mode": "dummy_dem", "steps": 60 },
    "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 2e-3, "initial_velocity": [%.17g, 0, 0],
               "boundary": { "xlo": { "type": "inlet", "velocity": [%.17g, 0, 0] },
                             "xhi": { "type": "outlet", "pressure": 0.0 } },
               "pressure": { "tol": 1e-12 } },
    "particles": { "dt": 5e-5,
      "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3 } ],
      "sources": [ { "type": "lattice", "lo": [0.0405, 0.0005, 0.0005], "counts": [40, 16, 16],
                     "spacing": [0.001, 0.001, 0.001], "radius": %.17g } ] },
    "coupling": { "drag": "gidaspow", "kernel": "trilinear" }
  })",
                u, u, 0.5 * kD);
  return buf;
}

}  // namespace

class Ergun : public ::testing::TestWithParam<double> {};

TEST_P(Ergun, BedPressureGradient) {
  const double u = GetParam();
  const Config cfg = test::caseFromText(bedCase(u));
  coupling::Simulation sim(Comm::world(), cfg);
  while (!sim.finished()) sim.step();
  // Least-squares slope over the bed interior (cells 12..17; the bed spans cells 10..19).
  const test::LayerGradient lg = test::layerGradient(sim, 12, 17, 16.0);
  const double slope = lg.slope, eps = lg.eps;
  const auto& dec = sim.decomposition();
  const double measured = -kRho * slope;
  const double ergun = 150.0 * kMu * (1 - eps) * (1 - eps) * u / (eps * eps * eps * kD * kD) +
                       1.75 * kRho * (1 - eps) * u * u / (eps * eps * eps * kD);
  if (dec.comm().isRoot())
    std::printf("Ergun bed U = %g m/s: eps %.4f, -dP/dx %.6g Pa/m, Ergun %.6g Pa/m, ratio %.4f\n",
                u, eps, measured, ergun, measured / ergun);
  EXPECT_NEAR(eps, 0.40, 0.005);
  EXPECT_NEAR(measured / ergun, 1.0, 0.05)
      << "U = " << u << " eps = " << eps << " measured " << measured << " Pa/m, Ergun " << ergun;
}

INSTANTIATE_TEST_SUITE_P(SuperficialVelocities, Ergun, ::testing::Values(0.002, 0.01, 0.05));
