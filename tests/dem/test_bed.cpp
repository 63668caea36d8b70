// Collective behaviour (issue 4):
//  - poured bed: spheres released in a periodic-x/y box settle on the floor under gravity; the
//    solid fraction of the bed's core (3 d above the floor to 3 d below the free surface, exact
//    sphere/slab intersection volumes) lies in [0.57, 0.64] (random loose-to-close packing of
//    frictional spheres, e.g. Onoda & Liniger 1990; Silbert et al. 2002).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dem_test_util.hpp"

namespace {

/// Volume of a sphere (centre height z, radius r) between the planes z = a and z = b.
double slabVolume(double z, double r, double a, double b) {
  const auto cap = [&](double h) {  // volume below height h (relative to the centre)
    h = std::clamp(h, -r, r);
    return M_PI * (r * r * (h + r) - (h * h * h + r * r * r) / 3.0);
  };
  return std::max(0.0, cap(b - z) - cap(a - z));
}

TEST(DemCollective, PouredBedSolidFraction) {
  // d = 1 mm, E = 5e6 Pa (the benchmark bed material), e = 0.5 to settle faster, mu = 0.5.
  const char* text = R"({
    "gravity": [0, 0, -9.81],
    "domain": {"length": [0.01, 0.01, 0.036], "cells": [4, 4, 12],
               "periodic": {"x": true, "y": true}},
    "particles": {"dt": 1e-5,
      "materials": [{"density": 2500, "young": 5e6, "poisson": 0.45, "restitution": 0.5,
                     "friction": 0.5}],
      "sources": [{"type": "random", "lo": [0, 0, 0.0005], "hi": [0.01, 0.01, 0.0355],
                   "count": 1500, "radius": 0.0005, "gap": 0.1, "velocity_spread": 0.05}]}})";
  demtest::Case run(text);
  for (int s = 0; s < 30000; ++s) run.dem->substep();
  auto& p = run.p();
  double top = 0;
  for (std::size_t i = 0; i < p.nOwned; ++i) top = std::max(top, p.x[2][i]);
  top = run.dec.comm().max(top);
  const double d = 0.001, a = 3 * d, b = top - 3 * d;
  double vol = 0;
  for (std::size_t i = 0; i < p.nOwned; ++i) vol += slabVolume(p.x[2][i], p.radius[i], a, b);
  vol = run.dec.comm().sum(vol);
  const double phi = vol / (0.01 * 0.01 * (b - a));
  const double ke = run.kinetic() / 1500.0;
  const auto diag = run.dem->diagnostics();
  if (run.dec.comm().isRoot())
    std::printf(
        "poured bed: height %.4f m, core solid fraction %.4f, kinetic energy per particle "
        "%.3e J, contacts/particle %.2f\n",
        top, phi, ke, diag["contacts_per_particle"].get<double>());
  EXPECT_GT(b - a, 5 * d);
  EXPECT_GE(phi, 0.57);  // reference range [0.57, 0.64]
  EXPECT_LE(phi, 0.64);
  EXPECT_LT(ke, 1e-9);  // settled: mean kinetic energy tiny against m g d = 1.3e-8 J
}

}  // namespace
