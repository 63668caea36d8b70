// Benchmark 1 (bench/cases/case1.json): one particle dragged across a process boundary.
// The run on this communicator (1, 2 or 4 ranks) is compared step by step with a serial run of
// the same case on every rank: particle position, velocity and coupling force equal to 1e-10
// relative, final fluid fields equal to 1e-10 relative, and the deposited solid volume equal to
// the particle volume at every step (no jump when the particle changes rank).
#include <cmath>
#include <numbers>

#include "coupled_util.hpp"

using namespace coloc;

namespace {

std::vector<double> globalPressure(coupling::Simulation& sim) {
  return test::globalCellValues(sim, sim.fluid()->fields().p);
}

}  // namespace

TEST(Case1, ParallelRunMatchesSerialStepByStep) {
  const Comm world = Comm::world();
  const test::SelfComm selfComm;
  const Comm self = selfComm.comm();
  // The pressure is solved to 1e-13 so that the fields of the two runs differ by round-off only.
  const std::vector<std::string> over = {"run.end_time=0.4", "run.progress_interval_s=0",
                                         "fluid.pressure.tol=1e-13"};
  const std::string path = COLOC_SOURCE_DIR "/bench/cases/case1.json";
  {
    const Config cfg = Config::load(world, path, over, coupling::caseSchema());
    coupling::Simulation par(world, cfg);
    coupling::Simulation ser(self, cfg);
    const double r = cfg.at("particles.sources")[0]["radius"].get<double>();
    const double vp = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    int firstOwner = -1, lastOwner = -1;
    double maxV = 0;
    while (!par.finished()) {
      par.step();
      ser.step();
      const auto a = test::particleState(par, 0), b = test::particleState(ser, 0);
      ASSERT_TRUE(a.found && b.found);
      for (int d = 0; d < 3; ++d) {
        ASSERT_NEAR(a.x[d], b.x[d], 1e-10 * std::abs(b.x[0])) << "step " << par.steps();
        ASSERT_NEAR(a.v[d], b.v[d], 1e-10 * (std::abs(b.v[0]) + 1e-30)) << "step " << par.steps();
        ASSERT_NEAR(a.f[d], b.f[d], 1e-10 * (std::abs(b.f[0]) + 1e-30)) << "step " << par.steps();
      }
      ASSERT_NEAR(par.depositedSolidVolume(), vp, 1e-12 * vp) << "step " << par.steps();
      const int owner = par.decomposition().ownerOfPoint({a.x[0], a.x[1], a.x[2]});
      if (firstOwner < 0) firstOwner = owner;
      lastOwner = owner;
      maxV = std::max(maxV, a.v[0]);
    }
    // The particle was dragged downstream and, in parallel, into another block.
    EXPECT_GT(maxV, 0.5);
    if (world.size() > 1) {
      EXPECT_NE(firstOwner, lastOwner);
    }
    const auto pp = globalPressure(par), ps = globalPressure(ser);
    double scale = 0;
    for (double v : ps) scale = std::max(scale, std::abs(v));
    for (std::size_t c = 0; c < pp.size(); ++c) ASSERT_NEAR(pp[c], ps[c], 1e-10 * scale) << c;
    EXPECT_LE(par.momentumBalance(), 1e-12);
  }
}
