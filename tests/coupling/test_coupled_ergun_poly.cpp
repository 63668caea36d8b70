// A fixed bidisperse bed (DummyDEM) of the Ergun test's lattice (tests/coupling/
// test_coupled_ergun.cpp), each sphere's diameter drawn from a discrete distribution
// (0.9 mm and 1.16 mm, equal numbers: the same solid fraction 0.60 on average), Gidaspow drag
// (Ergun branch) with each particle's own diameter. The steady pressure gradient in the bed
// interior is within 5 % of the Ergun equation with the Sauter mean diameter
// d32 = sum d^3 / sum d^2 of the bed's particles. (Summing the Ergun drag per particle gives the
// inertial term of Ergun(d32) exactly and its viscous term with 1/d^2 -> sum d / sum d^3, here
// 1.5 % above 1/d32^2; a drag law that used the largest or the smallest diameter for every
// particle would be 16 % low or 39 % high.)
#include <cmath>
#include <cstdio>
#include <numbers>

#include "coupled_util.hpp"

using namespace coloc;

namespace {

constexpr double kMu = 1e-3, kRho = 1000.0;

std::string bedCase(double u) {
  char buf[2048];
  // the lattice spheres overlap (d up to 1.16 mm at 1 mm spacing): a frozen bed, the overlap
  // check relaxed
  std::snprintf(buf, sizeof buf, R"({
    "domain": { "length": [0.12, 0.016, 0.016], "cells": [30, 4, 4],
                "periodic": { "y": true, "z": true } },
    "run": { "mode": "dummy_dem", "steps": 60 },
    "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 2e-3, "initial_velocity": [%.17g, 0, 0],
               "boundary": { "xlo": { "type": "inlet", "velocity": [%.17g, 0, 0] },
                             "xhi": { "type": "outlet", "pressure": 0.0 } },
               "pressure": { "tol": 1e-12 } },
    "particles": { "dt": 5e-5, "overlap_limit": 2.0,
      "materials": [ { "density": 2500.0, "young": 1e5, "poisson": 0.3 } ],
      "sources": [ { "type": "lattice", "lo": [0.0405, 0.0005, 0.0005], "counts": [40, 16, 16],
                     "spacing": [0.001, 0.001, 0.001],
                     "size": { "type": "discrete", "diameters": [0.9e-3, 1.16e-3] } } ] },
    "coupling": { "drag": "gidaspow", "kernel": "trilinear" }
  })",
                u, u);
  return buf;
}

}  // namespace

TEST(ErgunPolydisperse, BedPressureGradientWithSauterDiameter) {
  const double u = 0.002;  // particle Reynolds number ~2: the viscous term dominates
  const Config cfg = test::caseFromText(bedCase(u));
  coupling::Simulation sim(Comm::world(), cfg);
  // Sauter mean diameter of the bed and the two moments of the per-particle sum
  double mom[4] = {0, 0, 0, 0};
  {
    const auto& p = sim.particles()->particles();
    for (std::size_t i = 0; i < p.nOwned; ++i) {
      const double d = 2 * p.radius[i];
      mom[0] += d, mom[1] += d * d, mom[2] += d * d * d, mom[3] += 1;
    }
    sim.decomposition().comm().sumInPlace(std::span<double>(mom, 4));
  }
  const double d32 = mom[2] / mom[1];
  while (!sim.finished()) sim.step();
  // Least-squares slope over the bed interior (cells 12..17; the bed spans cells 10..19).
  const test::LayerGradient lg = test::layerGradient(sim, 12, 17, 16.0);
  const double slope = lg.slope, eps = lg.eps;
  const auto& dec = sim.decomposition();
  const double measured = -kRho * slope;
  const double e3 = eps * eps * eps;
  const double ergun = 150.0 * kMu * (1 - eps) * (1 - eps) * u / (e3 * d32 * d32) +
                       1.75 * kRho * (1 - eps) * u * u / (e3 * d32);
  const double sum = 150.0 * kMu * (1 - eps) * (1 - eps) * u / e3 * (mom[0] / mom[2]) +
                     1.75 * kRho * (1 - eps) * u * u / (e3 * d32);
  const double dmax = 1.16e-3;
  const double ergunMax = 150.0 * kMu * (1 - eps) * (1 - eps) * u / (e3 * dmax * dmax) +
                          1.75 * kRho * (1 - eps) * u * u / (e3 * dmax);
  if (dec.comm().isRoot())
    std::printf(
        "bidisperse Ergun bed U = %g m/s: %g particles, d32 %.5g mm, eps %.4f, -dP/dx %.6g "
        "Pa/m, Ergun(d32) %.6g (ratio %.4f), per-particle sum %.6g (ratio %.4f), "
        "Ergun(d_max) %.6g\n",
        u, mom[3], d32 * 1e3, eps, measured, ergun, measured / ergun, sum, measured / sum,
        ergunMax);
  EXPECT_NEAR(eps, 0.40, 0.01);
  EXPECT_NEAR(measured / ergun, 1.0, 0.05);
  EXPECT_GT(std::abs(measured / ergunMax - 1.0), 0.10);  // the test can tell the diameters apart
}
