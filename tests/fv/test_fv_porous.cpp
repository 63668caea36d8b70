// Darcy-Brinkman channel: uniform eps < 1 and uniform drag coefficient K (particles at rest,
// K u_p = 0), no-slip walls at y = 0 and y = H, periodic z, uniform inlet velocity U and a
// pressure outlet. Fully developed, the VANS momentum equation of docs/fv.md reduces to
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
    "domain": {"length": [3.0, 1.0, )" +
                           std::to_string(3 * h) + R"(], "cells": [)" + std::to_string(nx) + ", " +
                           std::to_string(N) + R"(, 3],
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
  auto& f = solver.edit();
  f.eps.fill(eps);
  f.K.fill(K);
  solver.syncEpsOld();
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

// Drag exchange bookkeeping for the coupling: triply periodic box, uniform eps = 0.7 (so the
// pressure term -eps grad p, convection and viscous fluxes sum to zero over the box), nonuniform
// K, particles moving at U_p (KUp = K U_p), fluid initially at rest, no gravity. The fluid
// momentum sum_f eps_f u_f V must change each step by exactly dt * drag_force (the diagnostics
// entry the coupling compares with the particles' drag impulse): to 1e-12 relative.
TEST(FvPorous, DragImpulseEqualsFluidMomentumChange) {
  const std::string text = R"({
    "run": {"mode": "fluid"},
    "domain": {"length": [1.0, 0.8, 0.6], "cells": [10, 8, 6],
               "periodic": {"x": true, "y": true, "z": true}},
    "fluid": {"nu": 0.01, "dt": 0.01, "pressure": {"tol": 1e-12}}
  })";
  const Config cfg = fvtest::config(text);
  const Decomposition dec = decompositionFromConfig(Comm::world(), cfg);
  Timers timers;
  fv::FluidSolver solver(dec, cfg, timers);
  const Real3 up{0.3, -0.2, 0.1};
  auto& f = solver.edit();
  forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    const Real3 x = fvtest::cellPos(dec, i, j, k);
    f.eps(i, j, k) = 0.7;
    f.K(i, j, k) = 5.0 + 2.0 * std::cos(2 * M_PI * x[2] / 0.6) * std::sin(2 * M_PI * x[0]);
    for (int c = 0; c < 3; ++c) f.KUp[c](i, j, k) = f.K(i, j, k) * up[c];
  });
  solver.syncEpsOld();
  auto momentum = [&]() {
    Real3 m{0, 0, 0};
    const auto& ff = std::as_const(solver).fields();
    for (int c = 0; c < 3; ++c)
      forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
        const int di = c == 0, dj = c == 1, dk = c == 2;
        const double ef = 0.5 * (ff.eps(i, j, k) + ff.eps(i - di, j - dj, k - dk));
        m[c] += ef * ff.u[c](i, j, k) * dec.grid().cellVolume();
      });
    for (auto& v : m) v = dec.comm().sum(v);
    return m;
  };
  double worst = 0;
  for (int n = 0; n < 5; ++n) {
    const Real3 m0 = momentum();
    solver.step(0.01);
    std::array<CellField, 3> uc;
    solver.cellVelocity(uc);  // fills the eps/u ghosts used by momentum()
    const Real3 m1 = momentum();
    const Json d = solver.diagnostics();
    for (int c = 0; c < 3; ++c) {
      const double impulse = 0.01 * d["fluid"]["drag_force"][c].get<double>();
      worst = std::max(worst, std::fabs((m1[c] - m0[c]) - impulse) / std::fabs(impulse));
    }
  }
  if (dec.comm().isRoot()) std::printf("drag impulse vs fluid momentum change: %.2e\n", worst);
  EXPECT_LE(worst, 1e-12);
}
