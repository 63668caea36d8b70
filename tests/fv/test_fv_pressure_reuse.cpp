// The pressure set-up reuse (fluid.pressure.setup_interval, setup_iteration_growth; docs/fv.md,
// "Pressure set-up reuse"), on a walled channel whose eps and K change every step (every step a
// new operator; a grid that PFMG coarsens on every axis, so that a kept hierarchy's coarse
// levels are not the current operator's), 1-3 ranks:
//  - every solve meets its tolerance: after each step (eps^{n+1}-eps^n)/dt + div(eps_f u) is
//    below 1.05 tol of the right-hand side's flux scale (PCG's stopping test), with one set-up
//    serving up to 8 operators as with a set-up every step; the set-ups counted are those
//    expected (1 in 8 steps; every step with setup_interval = 1), and the fields of both runs
//    agree to 1e-7 relative (the solver's tolerance is 1e-10: the two runs differ by solves that
//    each stopped somewhere below it);
//  - a solve that needs more iterations than the growth allows asks for a set-up before the next
//    operator (growth 1: any solve above the first solve's count + 1);
//  - a state copied into a new solver mid-way through a set-up's operators (the restart table
//    and the counters, as checkpoints and re-balancing do) continues bitwise as the run it was
//    copied from: the hierarchy is set up again on the operator of the last set-up;
//  - the multigrid cycle alone (krylov = none) and SMG with a kept hierarchy meet the tolerance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "fv_test_util.hpp"

using namespace coloc;

namespace {

constexpr double kTol = 1e-10;

/// A box of 1.6 x 1.2 x 0.8 m on 16 x 12 x 8 cells (multigrid coarsens every axis; 3 ranks cut
/// it unevenly): an inlet on xlo at (1, 0.1, 0.05) m/s, an outlet on xhi, walls elsewhere, the
/// ylo wall moving at 0.3 m/s along z. `extra`: more keys of fluid.pressure.
std::string reuseCase(long long interval, const std::string& extra = "") {
  return R"({
  "run": {"mode": "fluid"},
  "gravity": [0.0, -1.0, 0.0],
  "domain": {"length": [1.6, 1.2, 0.8], "cells": [16, 12, 8]},
  "fluid": {"nu": 0.01, "convection": "tvd", "adaptive_dt": true, "dt": 0.05, "cfl": 0.4,
            "pressure": {"tol": 1e-10, "max_iter": 400, "setup_interval": )" +
         std::to_string(interval) + extra + R"(},
            "boundary": {"xlo": {"type": "inlet", "velocity": [1.0, 0.1, 0.05]},
                         "xhi": {"type": "outlet"},
                         "ylo": {"type": "wall", "velocity": [0.0, 0.0, 0.3]},
                         "yhi": {"type": "wall"}, "zlo": {"type": "wall"},
                         "zhi": {"type": "wall"}}}
})";
}

/// The fluid fraction at x and time t (0.55 .. 0.95, moving).
double epsAt(const Real3& x, double t) {
  return 0.75 + 0.15 * std::sin(4.0 * x[0] - 3.0 * t) * std::cos(3.0 * x[1]) +
         0.05 * std::cos(2 * M_PI * x[2] / 0.8 + t);
}

/// eps^{n+1}(t), K and K u_p on owned cells: a new operator every step. kScale multiplies K's
/// variation (1e4: a drag-dominated operator, a jump of 0.5 .. 2e4 1/s across the box).
void setInputs(fv::FluidSolver& s, const Decomposition& dec, double t, double kScale = 1.0) {
  auto& f = s.edit();
  forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    const Real3 x = fvtest::cellPos(dec, i, j, k);
    f.eps(i, j, k) = epsAt(x, t);
    f.K(i, j, k) = 2.0 + kScale * (1.0 + std::sin(5 * x[0] - t) * std::sin(7 * x[1]));
    f.KUp[0](i, j, k) = 0.3 * f.K(i, j, k);
    f.KUp[1](i, j, k) = -0.1 * x[0] * f.K(i, j, k);
    f.KUp[2](i, j, k) = 0.05 * f.K(i, j, k);
  });
}

struct Channel {
  Config cfg;
  Decomposition dec;
  Timers timers;
  fv::FluidSolver solver;
  explicit Channel(const std::string& json)
      : cfg(fvtest::config(json)),
        dec(decompositionFromConfig(Comm::world(), cfg)),
        solver(dec, cfg, timers) {
    setInputs(solver, dec, 0.0);
    solver.syncEpsOld();
  }
  double kScale = 1.0;
  /// One step with this step's inputs; returns ||continuity||_2 / the flux scale.
  double step(double dtInputs = 0.01) {
    const double t = solver.time();
    setInputs(solver, dec, t + dtInputs, kScale);
    CellField epsN = std::as_const(solver).fields().epsOld;
    const double dt = solver.nextDt();
    solver.step(dt);
    std::array<CellField, 3> uc;
    solver.cellVelocity(uc);  // the high faces' ghosts
    const double cont = fvtest::continuityNorm(dec, std::as_const(solver).fields(), epsN, dt);
    const Json d = solver.diagnostics();
    return cont / d["pressure"]["rhs_scale_last"].get<double>();
  }
  long long setups() const { return solver.counters().setups; }
};

/// max over owned cells and faces of |a - b| / max|b| (same decomposition), over every rank.
double relativeDiff(const Channel& a, const Channel& b) {
  const auto& fa = std::as_const(a.solver).fields();
  const auto& fb = std::as_const(b.solver).fields();
  double diff = 0, ref = 0;
  const auto cmp = [&](const Field3<double>& x, const Field3<double>& y, const IndexBox& box) {
    forEach(box, [&](int i, int j, int k) {
      diff = std::max(diff, std::fabs(x(i, j, k) - y(i, j, k)));
      ref = std::max(ref, std::fabs(y(i, j, k)));
    });
  };
  for (int d = 0; d < 3; ++d) cmp(fa.u[d], fb.u[d], fvtest::ownedFaces(a.dec, d));
  cmp(fa.p, fb.p, IndexBox{{0, 0, 0}, a.dec.cells()});
  const Comm& c = a.dec.comm();
  return c.max(diff) / c.max(ref);
}

bool bitwiseEqual(const Channel& a, const Channel& b) {
  const auto& fa = std::as_const(a.solver).fields();
  const auto& fb = std::as_const(b.solver).fields();
  bool same = true;
  const auto cmp = [&](const Field3<double>& x, const Field3<double>& y, const IndexBox& box) {
    forEach(box, [&](int i, int j, int k) {
      const double vx = x(i, j, k), vy = y(i, j, k);
      if (std::memcmp(&vx, &vy, sizeof vx) != 0) same = false;
    });
  };
  for (int d = 0; d < 3; ++d) cmp(fa.u[d], fb.u[d], fvtest::ownedFaces(a.dec, d));
  cmp(fa.p, fb.p, IndexBox{{0, 0, 0}, a.dec.cells()});
  return a.dec.comm().min(same ? 1 : 0) == 1;
}

}  // namespace

TEST(FvPressureReuse, EverySolveMeetsTheToleranceWithFewerSetups) {
  constexpr int kSteps = 24;
  Channel reuse(reuseCase(8)), every(reuseCase(1));
  double worst = 0;
  for (int n = 0; n < kSteps; ++n) {
    const double cr = reuse.step(), ce = every.step();
    EXPECT_LE(cr, 1.05 * kTol) << "step " << n << " (setup_interval 8)";
    EXPECT_LE(ce, 1.05 * kTol) << "step " << n << " (setup_interval 1)";
    worst = std::max(worst, cr);
  }
  EXPECT_EQ(every.setups(), kSteps);
  // one set-up serves 8 operators; a growth-triggered set-up adds at most one per window
  EXPECT_GE(reuse.setups(), kSteps / 8);
  EXPECT_LE(reuse.setups(), kSteps / 4);
  const Json d = reuse.solver.diagnostics();
  EXPECT_EQ(d["pressure"]["setups"].get<long long>(), reuse.setups());
  EXPECT_EQ(d["pressure"]["setup_interval"].get<long long>(), 8);
  EXPECT_EQ(d["fluid"]["unconverged_solves"].get<long long>(), 0);
  const double rel = relativeDiff(reuse, every);
  EXPECT_LE(rel, 1e-7) << "fields of setup_interval 8 against 1";
  if (Comm::world().rank() == 0)
    std::printf(
        "24 steps: %lld set-ups (interval 8) against %lld; worst continuity %.2e of the "
        "flux scale; fields differ by %.2e\n",
        reuse.setups(), every.setups(), worst, rel);
}

TEST(FvPressureReuse, IterationGrowthAsksForASetup) {
  // growth 1: a set-up is due as soon as a solve needs more than the first solve's count + 1.
  // After 3 steps the drag becomes dominant and uneven: the hierarchy of the first operator
  // preconditions the new ones worse, and only the strict run sets up again.
  constexpr int kSteps = 10;
  Channel strict(reuseCase(1000, R"(, "setup_iteration_growth": 1.0)"));
  Channel lax(reuseCase(1000, R"(, "setup_iteration_growth": 1000.0)"));
  long long laxMax = 0, laxFirst = 0;
  for (int n = 0; n < kSteps; ++n) {
    if (n == 3) strict.kScale = lax.kScale = 1e4;
    EXPECT_LE(strict.step(), 1.05 * kTol) << "step " << n;
    EXPECT_LE(lax.step(), 1.05 * kTol) << "step " << n;
    const long long it = lax.solver.counters().itLast;
    if (n == 0) laxFirst = it;
    laxMax = std::max(laxMax, it);
  }
  EXPECT_EQ(lax.setups(), 1);  // the first operator's only
  ASSERT_GT(laxMax, laxFirst + 1) << "the kept hierarchy did not cost iterations: no test";
  EXPECT_GT(strict.setups(), 1);
  EXPECT_LT(strict.solver.counters().itSum, lax.solver.counters().itSum);
}

TEST(FvPressureReuse, RestoredStateContinuesBitwise) {
  // The state after 11 steps (set-ups at steps 1 and 9, two operators served since) copied into a
  // new solver, which sets the hierarchy up again on the operator of step 9: both go on
  // identically.
  Channel a(reuseCase(8)), b(reuseCase(8));
  for (int n = 0; n < 11; ++n) a.step();
  ASSERT_GT(a.solver.counters().setupReuses, 0);
  std::vector<const Field3<double>*> from;
  fv::forEachStateField(std::as_const(a.solver),
                        [&](const fv::FluidSolver::StateField& sf, const Field3<double>* const* p) {
                          for (int c = 0; c < sf.components; ++c) from.push_back(p[c]);
                        });
  std::size_t next = 0;
  bool sawSetupFields = false;
  fv::forEachStateField(b.solver,
                        [&](const fv::FluidSolver::StateField& sf, Field3<double>* const* p) {
                          if (std::string(sf.name) == "eps_setup") sawSetupFields = true;
                          for (int c = 0; c < sf.components; ++c) {
                            const auto src = from[next++]->data();
                            std::copy(src.begin(), src.end(), p[c]->data().begin());
                          }
                        });
  EXPECT_TRUE(sawSetupFields);
  ASSERT_EQ(next, from.size());
  b.solver.restoreState(a.solver.counters());
  const long long setupsBefore = b.setups();
  EXPECT_EQ(setupsBefore, a.setups());  // the rebuild is not counted
  for (int n = 0; n < 10; ++n) {
    a.step();
    b.step();
    ASSERT_TRUE(bitwiseEqual(a, b)) << "step " << 11 + n;
  }
  EXPECT_EQ(a.setups(), b.setups());
  EXPECT_GT(a.setups(), setupsBefore);  // the set-up of step 17, made by both
}

TEST(FvPressureReuse, StateWithoutSetupSetsUpAtTheNextStep) {
  // A state whose counters hold no set-up (a checkpoint written with setup_interval 1, or before
  // the reuse existed): the next step sets up, the solve meets its tolerance.
  Channel a(reuseCase(8));
  for (int n = 0; n < 3; ++n) a.step();
  auto c = a.solver.counters();
  c.setupDt = -1;
  a.solver.restoreState(c);
  const long long before = a.setups();
  EXPECT_LE(a.step(), 1.05 * kTol);
  EXPECT_EQ(a.setups(), before + 1);
}

TEST(FvPressureReuse, CycleAloneAndSmgMeetTheTolerance) {
  for (const char* extra : {R"(, "krylov": "none")", R"(, "solver": "smg")"}) {
    Channel r(reuseCase(6, extra));
    for (int n = 0; n < 12; ++n) EXPECT_LE(r.step(), 1.05 * kTol) << extra << " step " << n;
    EXPECT_LE(r.setups(), 4) << extra;
    EXPECT_EQ(r.solver.diagnostics()["fluid"]["unconverged_solves"].get<long long>(), 0);
  }
}
