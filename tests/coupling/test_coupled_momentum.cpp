// Momentum conservation of the drag exchange: over every coupled step, the momentum the fluid
// loses through its (semi-implicit) drag term equals the drag impulse the particles receive, to
// round-off (tolerance 1e-12 relative), at 1, 2 and 4 ranks, for both kernels and a nonlinear
// drag law, with and without the smoothing filter. Walls on two axes exercise the mirror fold at
// the box faces.
#include "coupled_util.hpp"

using namespace coloc;

namespace {
const char* kCase = R"({
  "domain": { "length": [0.08, 0.06, 0.05], "cells": [8, 6, 5], "periodic": { "x": true } },
  "run": { "steps": 4 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "initial_velocity": [0.02, 0.0, 0.0], "dt": 1e-3 },
  "particles": {
    "dt": 5e-5,
    "materials": [ { "density": 2500.0, "young": 1e6, "poisson": 0.3 } ],
    "sources": [ { "type": "random", "lo": [0.002, 0.002, 0.002], "hi": [0.078, 0.058, 0.048],
                   "count": 60, "radius": 0.0015, "velocity_spread": 0.05 } ]
  },
  "coupling": { "drag": "difelice" }
})";
}

class Momentum : public ::testing::TestWithParam<std::string> {};

TEST_P(Momentum, FluidLossEqualsParticleDragImpulse) {
  const auto param = GetParam();
  const auto colon = param.find(':');
  const std::string kernel = param.substr(0, colon);
  const std::string passes = colon == std::string::npos ? "0" : param.substr(colon + 1);
  const Config cfg = test::caseFromText(
      kCase, {"coupling.kernel=" + kernel, "coupling.smoothing_passes=" + passes});
  coupling::Simulation sim(Comm::world(), cfg);
  while (!sim.finished()) {
    sim.step();
    const auto p = sim.particleDragImpulse();
    const auto f = sim.fluidDragImpulse();
    double scale = 0;
    for (int d = 0; d < 3; ++d) scale = std::max(scale, std::abs(p[d]));
    ASSERT_GT(scale, 0.0);
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(p[d] + f[d], 0.0, 1e-12 * scale) << "axis " << d;
  }
  EXPECT_LE(sim.momentumBalance(), 1e-12);
  EXPECT_EQ(sim.particles()->globalCount(), 60);
}

// kernel[:smoothing passes]
INSTANTIATE_TEST_SUITE_P(Kernels, Momentum,
                         ::testing::Values("trilinear", "centroid", "trilinear:2", "centroid:3"));
