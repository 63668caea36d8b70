// Square duct with a uniform inlet velocity and a pressure outlet (the case-1 channel without
// particles, at Re = U D / nu = 10 so that it develops within ~1.2 D and about a thousand steps
// reach the steady state). 19 cells across (the MAC discretisation error of u_c is 2nd order:
// -1.69 % at 13 cells, -0.66 % at 21 cells), 47 cells (2.47 D) along the duct.
//  - Mass balance (exact discrete property of the projection): inflow - outflow through the box
//    faces equals d/dt int eps dV (= 0 here) to <= 1e-10 relative, every step.
//  - Fully developed flow: centreline velocity / mean velocity vs the series solution of the
//    laminar square duct (e.g. White, Viscous Fluid Flow, eq. 3-48, with a = b):
//      u(y,z) = 16 a^2 G/(mu pi^3) sum_{n odd} (-1)^((n-1)/2) n^-3 [1 - cosh(n pi z/2a)/cosh(n
//      pi/2)] cos(n pi y/2a) Q      = 4 a^4 G/(3 mu) [1 - 192/pi^5 sum_{n odd} n^-5 tanh(n pi/2)]
//    giving u_c / U_mean = 2.0962; required within 1 %.
#include <gtest/gtest.h>

#include <cmath>

#include "fv_test_util.hpp"

using namespace coloc;

namespace {

double seriesCentrelineRatio() {
  const double pi = M_PI;
  double uc = 0, q = 0;
  for (int n = 1; n < 400; n += 2) {
    const double sgn = ((n - 1) / 2) % 2 == 0 ? 1.0 : -1.0;
    uc += sgn / (n * n * n) * (1.0 - 1.0 / std::cosh(n * pi / 2));
    q += std::tanh(n * pi / 2) / std::pow(n, 5);
  }
  // a = 1, G/mu = 1: u_c = 16/pi^3 uc; U_mean = Q / 4 = (1/3)(1 - 192/pi^5 q).
  return (16.0 / (pi * pi * pi) * uc) / ((1.0 / 3.0) * (1.0 - 192.0 / std::pow(pi, 5) * q));
}

}  // namespace

TEST(FvChannel, DevelopingDuctMassBalanceAndCentreline) {
  const int N = 19;  // odd: a cell centre on the duct axis
  const int nx = 47;
  const double D = 1.0, U = 1.0, L = nx * D / N;
  const std::string text = R"({
    "run": {"mode": "fluid"},
    "domain": {"length": [)" +
                           std::to_string(L) + R"(, 1.0, 1.0], "cells": [)" + std::to_string(nx) +
                           ", " + std::to_string(N) + ", " + std::to_string(N) + R"(]},
    "fluid": {"nu": 0.1, "convection": "tvd", "adaptive_dt": true, "dt": 1.0, "cfl": 0.5,
              "pressure": {"tol": 1e-12},
              "boundary": {"xlo": {"type": "inlet", "velocity": [1.0, 0, 0]},
                           "xhi": {"type": "outlet"}}}
  })";
  const Config cfg = fvtest::config(text);
  const Decomposition dec = decompositionFromConfig(Comm::world(), cfg);
  Timers timers;
  fv::FluidSolver solver(dec, cfg, timers);
  double worstBalance = 0;
  long long steps = 0;
  for (; steps < 20000; ++steps) {
    solver.step(solver.nextDt());
    const Json d = solver.diagnostics();
    worstBalance = std::max(worstBalance, d["checks"]["mass_balance"].get<double>());
    if (steps > 10 && d["fluid"]["steady_residual"].get<double>() < 1e-7) break;
  }
  const Json d = solver.diagnostics();
  EXPECT_LT(steps, 20000);
  EXPECT_NEAR(d["fluid"]["inflow"].get<double>(), U * D * D, 1e-12);
  EXPECT_LE(worstBalance, 1e-10) << "inlet/outlet mass balance";

  // Centreline velocity at x = 2 D (1.7 development lengths downstream, 0.47 D before the
  // outlet; it changes by < 0.02 % beyond), against the series solution for the mean velocity U.
  const int ic = 2 * N;
  double uc = 0;
  const Int3 g{ic, N / 2, N / 2};
  Int3 l;
  bool mine = true;
  for (int a = 0; a < 3; ++a) {
    l[a] = g[a] - dec.lo()[a];
    mine = mine && l[a] >= 0 && l[a] < dec.cells()[a];
  }
  if (mine) uc = solver.fields().u[0](l[0], l[1], l[2]);
  uc = dec.comm().sum(uc);
  const double ref = seriesCentrelineRatio();
  if (dec.comm().isRoot())
    std::printf(
        "duct: t = %g, dt %g, %lld steps, worst mass balance %.2e, u_c/U = %.5f, series %.5f, "
        "error %.3f %%\n",
        d["fluid"]["time"].get<double>(), d["fluid"]["dt_last"].get<double>(), steps + 1,
        worstBalance, uc / U, ref, 100 * std::fabs(uc / U - ref) / ref);
  EXPECT_NEAR(ref, 2.0962, 1e-4);
  EXPECT_LE(std::fabs(uc / U - ref) / ref, 0.01);
}
