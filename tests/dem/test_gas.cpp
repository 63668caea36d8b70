// Collective behaviour (issue 4):
//  - elastic frictionless gas (e = 1, mu = 0, Hertz; dt ~ 1/100 of a contact), periodic box: total
//  energy (kinetic +
//    elastic energy of the contacts) drifts by less than 1e-5 relative over 10^4 steps;
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dem_test_util.hpp"

namespace {

TEST(DemCollective, ElasticGasEnergy) {
  const char* text = R"({
    "domain": {"length": [0.024, 0.024, 0.024], "cells": [8, 8, 8],
               "periodic": {"x": true, "y": true, "z": true}},
    "particles": {"dt": 2.5e-6,
      "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 1.0,
                     "friction": 0.0}],
      "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.024, 0.024, 0.024],
                   "count": 300, "radius": 0.001, "velocity_spread": 0.3}]}})";
  demtest::Case run(text);
  const double e0 = run.kinetic() + run.dem->contactEnergy();
  double worst = 0;
  long long contactsSeen = 0;
  for (int s = 1; s <= 10000; ++s) {
    run.dem->substep();
    contactsSeen += run.dem->localContacts();
    if (s % 500 == 0) {
      const double e = run.kinetic() + run.dem->contactEnergy();
      worst = std::max(worst, std::fabs(e - e0) / e0);
    }
  }
  contactsSeen = run.dec.comm().sum(contactsSeen);
  if (run.dec.comm().isRoot())
    std::printf(
        "elastic gas: max |E - E0|/E0 over 1e4 steps = %.3e (%lld contact-steps, %lld "
        "rebuilds)\n",
        worst, contactsSeen / 2, run.dem->rebuildCount());
  EXPECT_LT(worst, 1e-5);         // tolerance 1e-5 relative
  EXPECT_GT(contactsSeen, 1000);  // the gas collides
}

}  // namespace
