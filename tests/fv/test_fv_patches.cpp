// Inlet and outlet patches (fluid.patches) and the scale of checks.mass_balance.
//
//  - PatchInletOutlet: a box of 11 x 7 x 9 cells (no rank count divides it), walls everywhere,
//    an inlet patch of 5 x 3 cells in the middle of zlo (with a transverse velocity component)
//    and an outlet patch on the high-x part of zhi. Every step: the volume balance
//    |in - out - dV/dt| / scale <= 1e-10; the inflow is exactly U times the patch area; the
//    normal velocity is exactly 0 on the wall part of zhi and the outflow goes through the patch.
//    On 2, 3 and 4 ranks the blocks are cut through both patches ([2,1,1]: x 6/5, [1,3,1]:
//    y 3/2/2, [2,2,1]) and u, p must equal the serial run (same process, MPI_COMM_SELF) to
//    1e-10 relative.
//  - ClosedBoxBalance: walls everywhere, a fluid fraction that moves every step while its total
//    stays the same (a permutation of a fixed set of values): in = out = 0 and dV/dt is round-off,
//    so the balance must be round-off (< 1e-12), not |dV|/|dV| = 1; at least one step has a
//    non-zero dV/dt (otherwise the check could not tell the scales apart).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fv_test_util.hpp"

using namespace coloc;

namespace {

const char* kPatchCase = R"({
  "run": {"mode": "fluid"},
  "domain": {"length": [1.1, 0.7, 0.9], "cells": [11, 7, 9]},
  "fluid": {"nu": 0.01, "convection": "tvd", "adaptive_dt": true, "dt": 0.05, "cfl": 0.4,
            "pressure": {"tol": 1e-12},
            "patches": [
              {"type": "inlet", "face": "zlo", "min": [0.32, 0.22], "max": [0.78, 0.48],
               "velocity": [0.1, 0.0, 1.0]},
              {"type": "outlet", "face": "zhi", "min": [0.62, 0.0], "max": [1.1, 0.7]}]}
})";

constexpr double kInletArea = 5 * 3 * 0.01;  // 5 x 3 cells of 0.1 x 0.1 m

struct Solo {
  Decomposition dec;
  Timers timers;
  fv::FluidSolver solver;
  explicit Solo(const Comm& comm, const Config& cfg)
      : dec(decompositionFromConfig(comm, cfg)), solver(dec, cfg, timers) {}
};

double maxRelDiff(const Comm& world, const Decomposition& pa, const Field3<double>& a,
                  const Decomposition& pb, const Field3<double>& b, const IndexBox& owned) {
  double v[2] = {0, 0};
  forEach(owned, [&](int i, int j, int k) {
    const double vb =
        b(i + pa.lo()[0] - pb.lo()[0], j + pa.lo()[1] - pb.lo()[1], k + pa.lo()[2] - pb.lo()[2]);
    v[0] = std::max(v[0], std::fabs(a(i, j, k) - vb));
    v[1] = std::max(v[1], std::fabs(vb));
  });
  world.maxInPlace(std::span<double>(v, 2));
  return v[1] > 0 ? v[0] / v[1] : v[0];
}

}  // namespace

TEST(FvPatches, PatchInletOutletBalanceAndSerialEqual) {
  const Comm world = Comm::world();
  std::vector<std::string> ov;
  if (world.size() == 2) ov.push_back("partition.dims=[2,1,1]");
  if (world.size() == 3) ov.push_back("partition.dims=[1,3,1]");
  if (world.size() == 4) ov.push_back("partition.dims=[2,2,1]");
  Solo par(world, fvtest::config(kPatchCase, ov));
  Solo ser(Comm(MPI_COMM_SELF), fvtest::config(kPatchCase, {"partition.dims=[1,1,1]"}));
  double worstBalance = 0;
  for (int n = 0; n < 30; ++n) {
    const double dt = par.solver.nextDt();
    ASSERT_NEAR(dt, ser.solver.nextDt(), 1e-12 * dt);
    par.solver.step(dt);
    ser.solver.step(dt);
    const Json d = par.solver.diagnostics();
    worstBalance = std::max(worstBalance, d["checks"]["mass_balance"].get<double>());
    EXPECT_NEAR(d["fluid"]["inflow"].get<double>(), kInletArea, 1e-12) << "step " << n;
  }
  const Json d = par.solver.diagnostics();
  EXPECT_LE(worstBalance, 1e-10);
  EXPECT_GT(d["fluid"]["outflow"].get<double>(), 0.5 * kInletArea);

  // The zhi face: u_z = 0 exactly on its wall part; the patch carries all the outflow.
  const auto& f = std::as_const(par.solver).fields();
  const auto& g = par.dec.grid();
  double v[2] = {0, 0};  // max |u_z| on the wall part, outflow through the patch
  if (par.dec.atHighBoundary(2)) {
    const int kf = par.dec.cells()[2];
    forEach(IndexBox{{0, 0, kf}, {par.dec.cells()[0], par.dec.cells()[1], kf + 1}},
            [&](int i, int j, int k) {
              const double x = g.origin[0] + (par.dec.lo()[0] + i + 0.5) * g.spacing(0);
              const double uz = f.u[2](i, j, k);
              if (x >= 0.62)
                v[1] += f.eps(i, j, k - 1) * uz * g.spacing(0) * g.spacing(1);
              else
                v[0] = std::max(v[0], std::fabs(uz));
            });
  }
  double mx = v[0], out = v[1];
  mx = world.max(mx);
  out = world.sum(out);
  EXPECT_EQ(mx, 0.0) << "normal velocity on the wall part of zhi";
  EXPECT_NEAR(out, d["fluid"]["outflow"].get<double>(), 1e-12);

  double worst = 0;
  for (int c = 0; c < 3; ++c)
    worst = std::max(
        worst, maxRelDiff(world, par.dec, f.u[c], ser.dec, std::as_const(ser.solver).fields().u[c],
                          fvtest::ownedFaces(par.dec, c)));
  worst =
      std::max(worst, maxRelDiff(world, par.dec, f.p, ser.dec, std::as_const(ser.solver).fields().p,
                                 IndexBox{{0, 0, 0}, par.dec.cells()}));
  EXPECT_LE(worst, 1e-10) << "parallel vs serial";
  if (world.isRoot())
    std::printf(
        "%d ranks: inflow %.15g (patch area %.15g), outflow %.6g, worst balance %.2e, "
        "worst relative difference to serial %.2e\n",
        world.size(), d["fluid"]["inflow"].get<double>(), kInletArea,
        d["fluid"]["outflow"].get<double>(), worstBalance, worst);
}

TEST(FvPatches, ClosedBoxBalance) {
  const char* text = R"({
    "run": {"mode": "fluid"},
    "domain": {"length": [1.0, 0.8, 0.6], "cells": [10, 8, 6]},
    "fluid": {"nu": 0.01, "dt": 0.01, "cfl_max": 1e3, "pressure": {"tol": 1e-12}}
  })";
  const Comm world = Comm::world();
  Solo s(world, fvtest::config(text));
  // eps^n: a permutation of a fixed set of values that changes every step (the total stays the
  // same up to round-off, which the order of the sums brings in).
  auto setEps = [&](int n) {
    auto& f = s.solver.edit();
    forEach(IndexBox{{0, 0, 0}, s.dec.cells()}, [&](int i, int j, int k) {
      const int L = s.dec.lo()[0] + i + 10 * (s.dec.lo()[1] + j + 8 * (s.dec.lo()[2] + k));
      const int m = (7 * L + 37 * n) % 480;
      f.eps(i, j, k) = 0.65 + 0.34 * std::sin(1.37 * m);  // 0.31 .. 0.99: inexact differences
    });
  };
  setEps(0);
  s.solver.syncEpsOld();
  double worst = 0, maxRate = 0;
  for (int n = 1; n <= 10; ++n) {
    setEps(n);
    s.solver.step(0.01);
    const Json d = s.solver.diagnostics();
    EXPECT_EQ(d["fluid"]["inflow"].get<double>(), 0.0);
    EXPECT_EQ(d["fluid"]["outflow"].get<double>(), 0.0);
    worst = std::max(worst, d["checks"]["mass_balance"].get<double>());
    maxRate = std::max(maxRate, std::fabs(d["fluid"]["volume_rate"].get<double>()));
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(maxRate, 0.0) << "dV/dt exactly 0 every step: the test cannot tell the scales apart";
  if (world.isRoot())
    std::printf("closed box: worst mass balance %.2e, largest |dV/dt| %.2e m^3/s\n", worst,
                maxRate);
}
