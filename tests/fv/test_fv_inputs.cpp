// The coupling's way of giving the fluid its inputs (startCoupling(inputs), step(dt, inputs))
// against the edit() way (edit() + syncEpsOld()): the same steps bit for bit, and
// after startCoupling() eps has the ghosts a gather and the boundary conditions give it (the
// coupling reads them before the first step). A superficial inlet (its face velocity is U / eps
// of the adjacent cell) checks that writing the inputs refreshes the velocity ghosts too.
// Moving eps, nonuniform K and K u_p; 1 and 2 ranks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <utility>

#include "fv_test_util.hpp"

using namespace coloc;

namespace {

const char* kCase = R"({
  "run": {"mode": "fluid"},
  "gravity": [0.0, -1.0, 0.0],
  "domain": {"length": [1.1, 0.9, 0.7], "cells": [11, 9, 7], "periodic": {"z": true}},
  "fluid": {"nu": 0.01, "convection": "tvd", "adaptive_dt": true, "dt": 0.05, "cfl": 0.4,
            "pressure": {"tol": 1e-10},
            "boundary": {"xlo": {"type": "inlet", "velocity": [0.8, 0.1, 0.0],
                                 "superficial": true},
                         "xhi": {"type": "outlet"},
                         "ylo": {"type": "wall"},
                         "yhi": {"type": "slip"}}}
})";

/// eps^{n+1}(t), K and K u_p on owned cells.
void write(const Decomposition& dec, CellField& eps, CellField& K, std::array<CellField, 3>& KUp,
           double t) {
  forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    const Real3 x = fvtest::cellPos(dec, i, j, k);
    eps(i, j, k) = 0.7 + 0.2 * std::sin(4.0 * x[0] - 3.0 * t) * std::cos(3.0 * x[1]);
    K(i, j, k) = 2.0 + std::sin(5 * x[0]) * std::sin(7 * x[1]);
    KUp[0](i, j, k) = 0.3 * K(i, j, k);
    KUp[1](i, j, k) = -0.1 * x[0] * K(i, j, k);
    KUp[2](i, j, k) = 0.05 * K(i, j, k);
  });
}

bool same(const Field3<double>& a, const Field3<double>& b) {
  return a.data().size() == b.data().size() &&
         std::memcmp(a.data().data(), b.data().data(), a.data().size() * sizeof(double)) == 0;
}

}  // namespace

TEST(FvInputs, CouplingInputsEqualFieldsPath) {
  const Comm world = Comm::world();
  const Config cfg = fvtest::config(kCase);
  const Decomposition dec = decompositionFromConfig(world, cfg);
  Timers ta, tb, tc;
  fv::FluidSolver a(dec, cfg, ta), b(dec, cfg, tb), c(dec, cfg, tc);
  // b's inputs: the coupling's own fields (garbage in the ghosts: the fluid must not read them).
  const FieldLayout layout = b.fields().p.layout();
  CellField eps(layout), K(layout);
  std::array<CellField, 3> KUp{CellField(layout), CellField(layout), CellField(layout)};
  for (auto* g : {&eps, &K, &KUp[0], &KUp[1], &KUp[2]}) g->fill(-7.0);
  const fv::CouplingInputs in{eps, K, KUp};
  {
    auto& f = a.edit();
    write(dec, f.eps, f.K, f.KUp, 0.0);
    a.syncEpsOld();
    write(dec, eps, K, KUp, 0.0);
    b.startCoupling(in);
    auto& g = c.edit();
    write(dec, g.eps, g.K, g.KUp, 0.0);
    c.restoreState(c.counters());  // gathers and closes every cell input
  }
  EXPECT_TRUE(same(std::as_const(b).fields().eps, std::as_const(c).fields().eps))
      << "eps ghosts after startCoupling()";
  int bad = 0;
  for (int n = 0; n < 6; ++n) {
    const double dtA = a.nextDt(), dtB = b.nextDt();
    ASSERT_EQ(dtA, dtB);
    a.step(dtA);
    b.step(dtB, in);
    const auto& fa = std::as_const(a).fields();
    const auto& fb = std::as_const(b).fields();
    for (int d = 0; d < 3; ++d) bad += !same(fa.u[d], fb.u[d]);
    bad += !same(fa.p, fb.p) + !same(fa.eps, fb.eps) + !same(fa.epsOld, fb.epsOld);
    std::array<CellField, 3> ua, ub;
    a.cellVelocity(ua);
    b.cellVelocity(ub);
    for (int d = 0; d < 3; ++d) bad += !same(ua[d], ub[d]);
    // The next inputs.
    auto& f = a.edit();
    write(dec, f.eps, f.K, f.KUp, a.time());
    write(dec, eps, K, KUp, b.time());
  }
  EXPECT_EQ(world.sum(bad), 0);
  EXPECT_EQ(a.diagnostics().dump(), b.diagnostics().dump());
}
