// Darcy-Brinkman channel: uniform eps < 1 and uniform drag coefficient K (particles at rest,
// K u_p = 0), no-slip walls at y = 0 and y = H, periodic z, uniform inlet velocity U and a
// pressure outlet. Fully developed, the VANS momentum equation of SPEC section 1 reduces to
//   eps nu u'' - K u = eps dp/dx,
// whose solution with u(0) = u(H) = 0 and mean U is (lambda = sqrt(K / (eps nu)), s = lambda H/2)
//   u(y) = U [1 - cosh(lambda (y - H/2)) / cosh s] / (1 - tanh(s)/s),
//   dp/dx = -K U / (eps (1 - tanh(s)/s)).
// Requirement (issue 3): the pressure drop between x = L/4 and x = 3L/4 (cross-section means of
// the cell pressures) within 1 % of -dp/dx * L/2. eps = 0.6, s = 2.5 (Brinkman layers of
// 0.2 H), 24 cells across, L = 3 H.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "fv_test_util.hpp"

using namespace coloc;

TEST(FvPorous, DarcyBrinkmanPressureDrop) {
  const int N = 24, nx = 3 * N;
  const double H = 1.0, L = 3.0, U = 1.0, eps = 0.6, nu = 0.05, s = 2.5;
  const double lambda = 2 * s / H;
  const double K = eps * nu * lambda * lambda;
  const double h = H / N;
  const std::string text = R"({
    "run": {"mode": "fluid"},
    "domain": {"length": [3.0, 1.0, )" + std::to_string(3 * h) + R"(], "cells": [)" +
                           std::to_string(nx) + ", " + std::to_string(N) + R"(, 3],
               "periodic": {"z": true}},
    "fluid": {"nu": 0.05, "convection": "tvd", "adaptive_dt": true, "dt": 1.0,
              "pressure": {"tol": 1e-10},
              "boundary": {"xlo": {"type": "inlet", "velocity": [1.0, 0, 0]},
                           "xhi": {"type": "outlet"}}}
  })";
  const Config cfg = fvtest::config(text);
  const Decomposition dec = decompositionFromConfig(Comm::world(), cfg);
  Timers timers;
  fv::FluidSolver solver(dec, cfg, timers);
  auto& f = solver.fields();
  f.eps.fill(eps);
  f.K.fill(K);
  solver.syncEpsOld();
  solver.markCoefficientsChanged();
  const long long steps = fvtest::runSteady(solver, 1e-9, 50000);
  EXPECT_LT(steps, 50000);

  // Cross-section mean pressure at the cell columns i1 (x = L/4) and i2 (x = 3L/4).
  const int i1 = nx / 4, i2 = 3 * nx / 4;
  double p1 = 0, p2 = 0;
  const auto& p = std::as_const(solver).fields().p;
  forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    if (dec.lo()[0] + i == i1) p1 += p(i, j, k);
    if (dec.lo()[0] + i == i2) p2 += p(i, j, k);
  });
  const double nSec = 3.0 * N;
  p1 = dec.comm().sum(p1) / nSec;
  p2 = dec.comm().sum(p2) / nSec;
  const double dx = (i2 - i1) * L / nx;
  const double G = -K * U / (eps * (1 - std::tanh(s) / s));
  const double ref = -G * dx;
  const double err = std::fabs((p1 - p2) - ref) / ref;
  if (dec.comm().isRoot())
    std::printf("Darcy-Brinkman: %lld steps, dp = %.6f, analytic %.6f, error %.3f %%\n", steps,
                p1 - p2, ref, 100 * err);
  EXPECT_LE(err, 0.01);
}
