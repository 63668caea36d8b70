// The self-induced velocity correction (coupling.self_velocity = stokeslet, coupling/
// self_velocity.hpp): one sphere settling at d/h = 0.4 (Di Felice drag, terminal Re 0.08) in the
// box of test_coupled_settling (16 x 16 x 24 cells, walls 8 cells from the sphere, top outlet).
//  - without the correction it settles > 5 % faster than its drag law (the test sees the effect);
//  - with it, within 1 % of the drag law at 10, 25 and 50 particle response times tau (the
//    issue's criterion; measured -0.6 to -0.8 %, docs/coupling.md);
//  - serial and parallel runs with the correction equal to round-off (on 2 ranks);
//  - the response tables, the discrete build-up and the implicit-drag solve; the key's checks.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "coloc/core/error.hpp"
#include "coloc/coupling/drag.hpp"
#include "coloc/coupling/self_velocity.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

constexpr double kNu = 1e-6, kRhoF = 1000.0, kG = 9.81;

struct Sphere {
  double d, h, rhoP, vt, tau;
};

/// A sphere of diameter d on cells of h whose Di Felice terminal Reynolds number (eps = 1) is re.
Sphere sphere(double d, double dOverH, double re) {
  Sphere s{d, d / dOverH, 0, re * kNu / d, 0};
  const double vp = std::numbers::pi * d * d * d / 6.0;
  const double beta =
      coupling::dragCoefficient(coupling::DragLaw::DiFelice, 1.0, d, s.vt, kRhoF, kNu);
  s.rhoP = kRhoF + beta * s.vt / (kG * vp);
  s.tau = s.rhoP * vp / beta;
  return s;
}

std::string settlingCase(const Sphere& s, double endTime, const char* selfVelocity) {
  const double lx = 16 * s.h, lz = 24 * s.h;
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
    "coupling": { "drag": "difelice", "kernel": "trilinear", "self_velocity": "%s" }
  })",
                lx, lx, lz, endTime, s.tau / 8, s.tau / 80, s.rhoP, 0.5 * lx + 0.3 * s.h,
                0.5 * lx + 0.2 * s.h, 0.7 * lz, 0.5 * s.d, selfVelocity);
  return buf;
}

/// v / v_t at t = k tau for each k in `at` (the last one ends the run).
std::vector<double> settle(const Comm& comm, const Sphere& s, const std::vector<double>& at,
                           const char* selfVelocity) {
  const Config cfg = test::caseFromText(settlingCase(s, at.back() * s.tau, selfVelocity));
  coupling::Simulation sim(comm, cfg);
  std::vector<double> out;
  for (double k : at) {
    while (!sim.finished() && sim.time() < k * s.tau * (1 - 1e-9)) sim.step();
    const auto p = test::particleState(sim, 0);
    EXPECT_TRUE(p.found);
    EXPECT_LT(std::abs(p.v[0]), 1e-3 * std::abs(p.v[2]));
    out.push_back(-p.v[2] / s.vt);
  }
  return out;
}

}  // namespace

TEST(SelfVelocity, ResponseTable) {
  // At a cell centre the stencil is one cell: R = G(0); at a cell corner the mean of the table
  // with the weights 1/8 per stencil cell pair.
  const auto r0 = coupling::selfResponse({0.0, 0.0, 0.0});
  for (double v : r0) EXPECT_DOUBLE_EQ(v, coupling::kSelfGreen[0][0][0]);
  const auto rc = coupling::selfResponse({0.5, 0.5, 0.5});
  double mean = 0;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c) mean += coupling::kSelfGreen[a][b][c] / 8.0;
  for (double v : rc) EXPECT_NEAR(v, mean, 1e-15);
  // Anisotropic offsets: the response along an axis depends on which axis has which fraction.
  const auto ra = coupling::selfResponse({0.5, 0.0, 0.0});
  EXPECT_NEAR(ra[0], 0.5 * (coupling::kSelfGreen[0][0][0] + coupling::kSelfGreen[1][0][0]), 1e-15);
  EXPECT_NEAR(ra[1], 0.5 * (coupling::kSelfGreen[0][0][0] + coupling::kSelfGreen[0][1][0]), 1e-15);
  // Equivalent Gaussian widths between 1/3 and 4/5 of a cell; the build-up of a Gaussian.
  EXPECT_NEAR(coupling::equivalentWidth(r0[0]), 0.335, 1e-3);
  EXPECT_NEAR(coupling::equivalentWidth(rc[0]), 0.764, 1e-3);
  EXPECT_DOUBLE_EQ(coupling::buildUp(1.0, 1.0, 0.0), 0.0);
  EXPECT_NEAR(coupling::buildUp(1.0, 1.0, 1.5), 0.5, 1e-15);  // sigma / sqrt(4 sigma^2)
  // The discrete build-up: zero at t = 0, the table's node at nu t / h^2 = 1, increasing, and
  // the steady table at long times (free-space 1/sqrt(s) tail past s = 16).
  EXPECT_DOUBLE_EQ(coupling::discreteGreen(0, 0, 0, 0.0), 0.0);
  EXPECT_NEAR(coupling::discreteGreen(0, 0, 0, 1.0), 0.0948804, 1e-12);
  double last = 0;
  for (double sv = 1e-3; sv < 1e3; sv *= 1.3) {
    const double g = coupling::discreteGreen(0, 0, 0, sv);
    EXPECT_GT(g, last) << "s = " << sv;
    last = g;
  }
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        EXPECT_NEAR(coupling::discreteGreen(a, b, c, 1e8), coupling::kSelfGreen[a][b][c], 1e-5);
  // Without implicit feedback (beta_eff -> 0), long after the start, the mobility is the steady
  // table's R / (mu h eps) and the pressure response w Q w / (h^3 eps); with the feedback the
  // mobility is lower (the particle's own disturbance lowers the force the fluid takes).
  const std::array<double, 3> tt{0.8, 0.7, 0.8};
  const double rz = coupling::selfResponse(tt)[2];
  const auto bare = coupling::selfMobility(tt, {0, 0, 1}, 2.0, 3.0, 1.0, 0.5, 1e12, 0.0);
  EXPECT_NEAR(bare.mobility * 2.0 * 3.0 * 0.5 / rz, 1.0, 1e-6);
  double wqw = 0;
  for (int o = 0; o < 8; ++o)
    for (int q = 0; q < 8; ++q) {
      double wo = 1, wq = 1;
      for (int d = 0; d < 3; ++d) {
        wo *= (o >> d & 1) ? tt[d] : 1 - tt[d];
        wq *= (q >> d & 1) ? tt[d] : 1 - tt[d];
      }
      const int x = o ^ q;
      wqw += wo * wq * coupling::discretePressure(x >> 2 & 1, x & 1, x >> 1 & 1);
    }
  EXPECT_NEAR(bare.pressure[2] * 8.0 * 0.5 / wqw, 1.0, 1e-12);
  const auto fed =
      coupling::selfMobility(tt, {0, 0, 1}, 2.0, 3.0, 1.0, 0.5, 1e12, 0.25 * 3.0 * 2.0 * 0.5 / rz);
  EXPECT_LT(fed.mobility, bare.mobility);
  EXPECT_GT(fed.mobility, 0.95 * bare.mobility);
}

TEST(SelfVelocity, KeyChecks) {
  const Sphere s = sphere(4e-5, 0.4, 0.08);
  const std::string text = settlingCase(s, s.tau, "stokeslet");
  auto expectError = [&](std::vector<std::string> set, const char* what) {
    try {
      const Config cfg = test::caseFromText(text, set);
      coupling::selfVelocityFromConfig(cfg);
      ADD_FAILURE() << "no error for " << what;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("coupling.self_velocity"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expectError({"coupling.kernel=centroid"}, "trilinear");
  expectError({"coupling.smoothing_passes=1"}, "smoothing");
  expectError({"domain.cells=[16,16,20]"}, "cubic");
  EXPECT_EQ(coupling::selfVelocityFromConfig(test::caseFromText(text)),
            coupling::SelfVelocity::Stokeslet);
  EXPECT_EQ(coupling::selfVelocityFromConfig(test::caseFromText(
                text, {"coupling.self_velocity=none", "coupling.kernel=centroid"})),
            coupling::SelfVelocity::None);
}

TEST(SelfVelocity, SettlingAtDOverH04) {
  // Compared with the drag law at eps = 1: an isolated sphere; with the correction the drag law
  // sees the fluid fraction without the sphere's own volume (docs/coupling.md).
  const Comm world = Comm::world();
  const Sphere s = sphere(4e-5, 0.4, 0.08);
  const std::vector<double> at = {10, 25, 50};
  const auto off = settle(world, s, at, "none");
  const auto on = settle(world, s, at, "stokeslet");
  for (std::size_t k = 0; k < at.size(); ++k)
    std::printf("d/h 0.4, Re 0.08: t = %3.0f tau  v/v_t  none %.4f  stokeslet %.4f\n", at[k],
                off[k], on[k]);
  EXPECT_GT(off[1], 1.05) << "the uncorrected sphere no longer shows its self-induced velocity";
  // The issue's criterion: within 1 % of the drag law (measured 0.9917, 0.9940, 0.9928).
  for (std::size_t k = 0; k < at.size(); ++k)
    EXPECT_NEAR(on[k], 1.0, 0.01) << "t = " << at[k] << " tau";
}

TEST(SelfVelocity, SettlingAtDOverH02) {
  const Comm world = Comm::world();
  // A figure of docs/coupling.md; the parallel path is SerialEqualsParallel's.
  if (world.size() > 1) GTEST_SKIP() << "one rank";
  const Sphere s = sphere(4e-5, 0.2, 0.08);
  const std::vector<double> at = {10, 25, 50};
  const auto off = settle(world, s, at, "none");
  const auto on = settle(world, s, at, "stokeslet");
  for (std::size_t k = 0; k < at.size(); ++k)
    std::printf("d/h 0.2, Re 0.08: t = %3.0f tau  v/v_t  none %.4f  stokeslet %.4f\n", at[k],
                off[k], on[k]);
  // Measured 0.9983, 0.9987, 0.9987.
  for (std::size_t k = 0; k < at.size(); ++k) {
    EXPECT_NEAR(on[k], 1.0, 0.005) << "t = " << at[k] << " tau";
    if (at[k] >= 25) {
      EXPECT_LT(std::abs(on[k] - 1.0), std::abs(off[k] - 1.0)) << "t = " << at[k] << " tau";
    }
  }
}

TEST(SelfVelocity, SerialEqualsParallel) {
  const Comm world = Comm::world();
  if (world.size() == 1) GTEST_SKIP() << "needs 2 ranks";
  const test::SelfComm selfComm;
  {
    const Sphere s = sphere(4e-5, 0.4, 0.08);
    const std::vector<double> at = {5};
    const auto par = settle(world, s, at, "stokeslet");
    const auto ser = settle(selfComm.comm(), s, at, "stokeslet");
    EXPECT_NEAR(par[0], ser[0], 1e-12);
  }
}

TEST(SelfVelocity, FrozenSphereFollowsTheTable) {
  // The model against the solver: a frozen sphere (dummy_dem, Stokes drag, no correction) in a
  // periodic 32^3 box, the fluid started at U along z (cell Re 0.02). Its disturbance
  // c beta = (U - u_at) / u_at (u_at from the drag it receives) against the model's c(t) beta
  // (discrete build-up, implicit drag with beta_eff = beta): measured 0.8 % and 1.4 % above at
  // nu t / h^2 = 1.5 and 3 (the model's 1/eps, docs/coupling.md).
  if (Comm::world().size() > 1)
    GTEST_SKIP() << "one rank (the parallel path: SerialEqualsParallel)";
  const Sphere s = sphere(4e-5, 0.4, 0.08);
  const double lx = 32 * s.h, tEnd = 3.0 * s.h * s.h / kNu;
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"({
    "domain": { "length": [%.17g, %.17g, %.17g], "cells": [32, 32, 32],
                "periodic": { "x": true, "y": true, "z": true } },
    "gravity": [0.0, 0.0, 0.0],
    "run": { "steps": 0, "end_time": %.17g, "mode": "dummy_dem" },
    "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": %.17g, "initial_velocity": [0, 0, %.17g],
               "pressure": { "tol": 1e-12 } },
    "particles": { "dt": %.17g, "bin_cells": 1,
      "materials": [ { "density": %.17g, "young": 1e3, "poisson": 0.3, "restitution": 0.9 } ],
      "sources": [ { "type": "list", "positions": [%.17g, %.17g, %.17g], "radius": %.17g } ] },
    "coupling": { "drag": "stokes", "kernel": "trilinear" }
  })",
                lx, lx, lx, tEnd, s.tau / 4, 0.1 * s.vt, s.tau / 40, s.rhoP, 16.3 * s.h, 16.2 * s.h,
                16.3 * s.h, 0.5 * s.d);
  const Config cfg = test::caseFromText(buf);  // the Simulation keeps a reference to it
  coupling::Simulation sim(Comm::world(), cfg);
  const double mu = kRhoF * kNu, beta = 3 * std::numbers::pi * mu * s.d;
  const std::array<double, 3> t{0.8, 0.7, 0.8};
  double sumW2 = 1;
  for (double f : t) sumW2 *= (1 - f) * (1 - f) + f * f;
  const double eps = 1 - std::numbers::pi * s.d * s.d * s.d / 6 / std::pow(s.h, 3) * sumW2;
  for (double T : {1.5, 3.0}) {
    while (sim.time() < T * s.h * s.h / kNu * (1 - 1e-9)) sim.step();
    const auto p = test::particleState(sim, 0);
    const double uAt = p.f[2] / beta;
    const double measured = (0.1 * s.vt - uAt) / uAt;
    const double model =
        coupling::selfMobility(t, {0, 0, 1}, s.h, mu, kNu, eps, sim.time(), beta).mobility * beta;
    std::printf("frozen sphere, nu t/h^2 = %.1f: c beta solver %.4f, model %.4f\n", T, measured,
                model);
    EXPECT_NEAR(model / measured, 1.0, 0.025) << "nu t / h^2 = " << T;
  }
}
