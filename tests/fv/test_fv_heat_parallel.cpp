// The fluid energy equation in parallel: serial = 2, 3, 4 ranks.
//
// The open channel of test_fv_heat (inlet at 350 K, outlet, a wall at 300 K, a moving lid,
// periodic z, moving eps, a heat source) on 13 x 9 x 7 cells, whose blocks do not divide
// evenly. Every rank also runs the case alone (MPI_COMM_SELF); the owned temperatures must
// equal the serial ones to <= 1e-12 relative, the tolerance of the velocity they are advected
// with (test_fv_parallel: the pressure solves of different decompositions agree to their
// tolerance, not bitwise), and the energy balance of the parallel run must close to <= 1e-12.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "fv_test_util.hpp"

using namespace coloc;

namespace {

const std::string kCase = fvtest::heatChannelCase("1e-12");

void setInputs(fv::FluidSolver& s, const Decomposition& dec, double t) {
  auto& f = s.edit();
  forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    const Real3 x = fvtest::cellPos(dec, i, j, k);
    f.eps(i, j, k) = fvtest::channelEps(x, t);
    f.heatSource(i, j, k) = 0.02 * (1.0 + std::sin(5 * x[0]) * std::cos(3 * x[1]));
  });
}

struct Solo {
  Decomposition dec;
  Timers timers;
  fv::FluidSolver solver;
  Solo(const Comm& comm, const Config& cfg)
      : dec(decompositionFromConfig(comm, cfg)), solver(dec, cfg, timers) {}
};

}  // namespace

TEST(FvHeatParallel, SameTemperatureAsSerial) {
  const Comm world = Comm::world();
  std::vector<std::string> overrides;
  if (world.size() == 4) overrides.push_back("partition.dims=[2,1,2]");  // split periodic z too
  Solo par(world, fvtest::config(kCase, overrides));
  Solo ser(Comm(MPI_COMM_SELF), fvtest::config(kCase, {"partition.dims=[1,1,1]"}));
  for (auto* s : {&par, &ser}) {
    setInputs(s->solver, s->dec, 0.0);
    s->solver.syncEpsOld();
  }
  for (int n = 0; n < 12; ++n) {
    const double dt = par.solver.nextDt();
    for (auto* s : {&par, &ser}) {
      setInputs(s->solver, s->dec, s->solver.time() + 0.01);
      s->solver.step(dt);
    }
  }
  const auto& Tp = par.solver.fields().T;
  const auto& Ts = ser.solver.fields().T;
  double diff = 0, ref = 0;
  const Int3 lo = par.dec.lo();
  forEach(IndexBox{{0, 0, 0}, par.dec.cells()}, [&](int i, int j, int k) {
    diff = std::max(diff, std::fabs(Tp(i, j, k) - Ts(i + lo[0], j + lo[1], k + lo[2])));
    ref = std::max(ref, std::fabs(Ts(i + lo[0], j + lo[1], k + lo[2])));
  });
  diff = world.max(diff);
  ref = world.max(ref);
  const Json d = par.solver.diagnostics();
  const double balance = d["checks"]["fluid_energy_balance"].get<double>();
  if (world.isRoot())
    std::printf("%d ranks (%s): max |T - T_serial| / max|T| = %.2e; energy balance %.2e\n",
                world.size(), par.dec.shape().c_str(), diff / ref, balance);
  EXPECT_LE(diff, 1e-12 * ref);
  EXPECT_LE(balance, 1e-12);
  // The ghosts of T are current after a step (the coupling samples them): equal to the
  // neighbour's owned values, i.e. to the serial field, on the halo layers inside the box.
  double ghostDiff = 0;
  const Int3 n = par.dec.cells(), g = par.dec.grid().cells;
  forEach(IndexBox{{-1, -1, -1}, {n[0] + 1, n[1] + 1, n[2] + 1}}, [&](int i, int j, int k) {
    int gi[3] = {i + lo[0], j + lo[1], k + lo[2]};
    for (int a = 0; a < 3; ++a) {
      if (par.dec.grid().periodic[a]) gi[a] = (gi[a] + g[a]) % g[a];
      if (gi[a] < 0 || gi[a] >= g[a]) return;  // beyond a physical face: boundary ghosts
    }
    ghostDiff = std::max(ghostDiff, std::fabs(Tp(i, j, k) - Ts(gi[0], gi[1], gi[2])));
  });
  EXPECT_LE(world.max(ghostDiff), 1e-12 * ref);
}
