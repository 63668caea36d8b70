// Serial vs parallel, and discrete continuity with a prescribed time-varying eps.
//
// One case that exercises every term: inlet (with a transverse component) / outlet along x,
// a no-slip wall and a moving lid along y, periodic z; TVD convection, gravity, a nonuniform
// eps(x, t) that changes every step, nonuniform K and K u_p; adaptive dt. 13 x 9 x 7 cells, so
// the 2- and 4-rank blocks are uneven (7/6 along x, 5/4 along y or 4/3 along the periodic z).
//  - Every rank also runs the case alone (MPI_COMM_SELF); the owned values of u, p, the cell
//    velocity and the pressure gradient must equal the serial ones to <= 1e-10 relative
//    (requirement of issue 3), on the process grid the case chooses and on a tiled layout
//    (general boxes from the bisection of a clustered cost: neighbours across edges and
//    corners, any rank count; issue 14).
//  - The same with a superficial inlet (face velocity U / eps) on cuts that leave the inlet's
//    block and the outlet's block 2 cells thick, the ghost width (1-5 ranks).
//  - After every step, per cell: (eps^{n+1} - eps^n)/dt + div(eps_f u^{n+1}) = 0 up to the
//    pressure solver's tolerance: ||.||_2 <= 1.05 tol * (flux scale of the right-hand side),
//    which is PCG's stopping test (fluid.pressure.tol = 1e-10 here).
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "coloc/partition/tiled.hpp"
#include "fv_test_util.hpp"
#include "tiled_layouts.hpp"

using namespace coloc;

namespace {

const std::string kCase = fvtest::channelCase(R"("convection": "tvd", )", R"("tol": 1e-10)");

constexpr int kSteps = 12;
constexpr double kTol = 1e-10;

/// Set eps^{n+1}(t), K and K u_p on owned cells.
void setInputs(fv::FluidSolver& s, const Decomposition& dec, double t) {
  auto& f = s.edit();
  forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    const Real3 x = fvtest::cellPos(dec, i, j, k);
    f.eps(i, j, k) = fvtest::channelEps(x, t);
    f.K(i, j, k) = 2.0 + std::sin(5 * x[0]) * std::sin(7 * x[1]);
    f.KUp[0](i, j, k) = 0.3 * f.K(i, j, k);
    f.KUp[1](i, j, k) = -0.1 * x[0] * f.K(i, j, k);
    f.KUp[2](i, j, k) = 0.05 * f.K(i, j, k);
  });
}

struct Solo {
  Decomposition dec;
  Timers timers;
  fv::FluidSolver solver;
  std::array<CellField, 3> uc, gp;
  explicit Solo(const Comm& comm, const Config& cfg)
      : dec(decompositionFromConfig(comm, cfg)), solver(dec, cfg, timers) {}
  Solo(Decomposition d, const Config& cfg) : dec(std::move(d)), solver(dec, cfg, timers) {}
};

/// The bisection's boxes for the communicator's ranks on a cost heaped in one corner.
Decomposition tiledDecomposition(const Comm& world, const GlobalGrid& g) {
  const auto cost = test::heapedCost(g, {6, 4, g.cells[2]}, 6.0);
  return decompositionOf(world, tiledBoxes(g, cost, world.size(), {}).layout);
}

/// Max over this rank's owned entries of |a - b| and of |b|, with a on `pa` and b on `pb`
/// (different decompositions of the same grid; b is the serial run).
void compare(const Decomposition& pa, const Field3<double>& a, const Decomposition& pb,
             const Field3<double>& b, const IndexBox& owned, double& diff, double& ref) {
  forEach(owned, [&](int i, int j, int k) {
    const double va = a(i, j, k);
    const double vb =
        b(i + pa.lo()[0] - pb.lo()[0], j + pa.lo()[1] - pb.lo()[1], k + pa.lo()[2] - pb.lo()[2]);
    diff = std::max(diff, std::fabs(va - vb));
    ref = std::max(ref, std::fabs(vb));
  });
}

}  // namespace

/// Steps the case on `par` and alone on this rank, checks continuity every step and the fields
/// against the serial run at the end.
void compareWithSerial(Solo& par, std::vector<std::string> overrides = {}) {
  const Comm world = Comm::world();
  overrides.push_back("partition.dims=[1,1,1]");
  const Config serialCfg = fvtest::config(kCase, overrides);
  Solo ser(Comm(MPI_COMM_SELF), serialCfg);
  setInputs(par.solver, par.dec, 0.0);
  setInputs(ser.solver, ser.dec, 0.0);
  par.solver.syncEpsOld();
  ser.solver.syncEpsOld();
  CellField epsN(cellLayout(par.dec, 2));
  double worstCont = 0;
  for (int n = 0; n < kSteps; ++n) {
    const double t = par.solver.time();
    setInputs(par.solver, par.dec, t + 0.01);
    setInputs(ser.solver, ser.dec, t + 0.01);
    epsN = std::as_const(par.solver).fields().epsOld;
    const double dt = par.solver.nextDt();
    const double dts = ser.solver.nextDt();
    ASSERT_NEAR(dt, dts, 1e-12 * dt);
    par.solver.step(dt);
    ser.solver.step(dt);
    // Fill u's ghosts (the high faces of the block) through cellVelocity, then check continuity.
    par.solver.cellVelocity(par.uc);
    const double cont =
        fvtest::continuityNorm(par.dec, std::as_const(par.solver).fields(), epsN, dt);
    const Json d = par.solver.diagnostics();
    const double bound = 1.05 * kTol * d["pressure"]["rhs_scale_last"].get<double>();
    EXPECT_LE(cont, bound) << "step " << n;
    worstCont = std::max(worstCont, cont / d["pressure"]["rhs_scale_last"].get<double>());
    EXPECT_LE(d["checks"]["mass_balance"].get<double>(), 1e-8) << "step " << n;
  }
  ser.solver.cellVelocity(ser.uc);
  par.solver.pressureGradient(par.gp);
  ser.solver.pressureGradient(ser.gp);
  const auto& fp = std::as_const(par.solver).fields();
  const auto& fs = std::as_const(ser.solver).fields();
  double worst = 0;
  auto check = [&](const char* what, const Field3<double>& a, const Field3<double>& b,
                   const IndexBox& owned) {
    double diff = 0, ref = 0;
    compare(par.dec, a, ser.dec, b, owned, diff, ref);
    diff = world.max(diff);
    ref = world.max(ref);
    EXPECT_LE(diff, 1e-10 * ref) << what;
    worst = std::max(worst, diff / ref);
  };
  const IndexBox cells{{0, 0, 0}, par.dec.cells()};
  for (int c = 0; c < 3; ++c) check("u", fp.u[c], fs.u[c], fvtest::ownedFaces(par.dec, c));
  check("p", fp.p, fs.p, cells);
  for (int c = 0; c < 3; ++c) check("cell velocity", par.uc[c], ser.uc[c], cells);
  for (int c = 0; c < 3; ++c) check("pressure gradient", par.gp[c], ser.gp[c], cells);
  if (world.isRoot())
    std::printf(
        "%d ranks (%s): worst relative difference to serial %.2e; worst continuity residual "
        "/ flux scale %.2e (tol %.0e)\n",
        world.size(), par.dec.shape().c_str(), worst, worstCont, kTol);
}

TEST(FvParallel, SameFieldsAsSerialAndContinuityWithMovingEps) {
  const Comm world = Comm::world();
  if (world.size() == 7)
    GTEST_SKIP() << "13 x 9 x 7 cells hold no process grid of 7 ranks with 2-cell blocks; "
                    "the tiled test covers 7 ranks";
  std::vector<std::string> overrides;
  if (world.size() == 4) overrides.push_back("partition.dims=[2,1,2]");  // split periodic z too
  const Config cfg = fvtest::config(kCase, overrides);
  Solo par(world, cfg);
  compareWithSerial(par);
}

TEST(FvParallel, TiledLayoutGivesTheSerialFields) {
  const Comm world = Comm::world();
  const Config cfg = fvtest::config(kCase);
  Solo par(tiledDecomposition(world, gridFromConfig(cfg)), cfg);
  ASSERT_TRUE(par.dec.isTiled());
  compareWithSerial(par);
}

TEST(FvParallel, SuperficialInletNextToABlockTwoCellsThick) {
  // A superficial inlet (its face carries U / eps of the adjacent cell, and eps moves every
  // step) on a block only 2 cells thick, the ghost width: the next block's ghost faces reach
  // the inlet face itself, so the halo must carry the face for the current eps. A block of 2
  // cells at the outlet too. (Blocks thinner than the ghost width are refused by the halo.)
  const Comm world = Comm::world();
  const int p = world.size();
  if (p > 5)
    GTEST_SKIP() << "13 cells along x hold at most 5 blocks with 2-cell blocks at both ends "
                    "and no block under 2 cells";
  const std::vector<std::string> overrides{"fluid.boundary.xlo.superficial=true"};
  const Config cfg = fvtest::config(kCase, overrides);
  const GlobalGrid g = gridFromConfig(cfg);
  std::array<std::vector<int>, 3> cuts{std::vector<int>{0}, std::vector<int>{0, g.cells[1]},
                                       std::vector<int>{0, g.cells[2]}};
  if (p >= 2) cuts[0].push_back(2);
  // Ranks 1 .. p-2 share cells [2, 11) evenly; the last block is [11, 13) (or [2, 13) at 2).
  for (int r = 2; r < p; ++r) cuts[0].push_back(2 + 9 * (r - 1) / (p - 2));
  cuts[0].push_back(g.cells[0]);
  Solo par(Decomposition::fromCuts(world, g, cuts), cfg);
  if (p >= 2 && (world.rank() == 0 || (p >= 3 && world.rank() == p - 1))) {
    EXPECT_EQ(par.dec.cells()[0], 2);
  }
  compareWithSerial(par, overrides);
}
