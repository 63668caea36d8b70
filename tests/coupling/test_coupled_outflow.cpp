// Benchmark 1 (bench/cases/case1.json) with an outflow outlet (particles.boundary.xhi =
// outflow): the sphere is dragged downstream and leaves through the outlet face. The run on this
// communicator (1, 2 or 4 ranks) is compared step by step with a serial run: position, velocity
// and coupling force equal to 1e-10 relative while the particle is in the box, removed at the
// same step, the deposited solid volume the particle's volume before and 0 from the step after, the
// count and mass reports (1 out through xhi, mass out = the particle's mass, mass held 0, balance
// 0), and the final pressure field equal to 1e-10 relative (after the particle left).
#include <cmath>
#include <numbers>

#include "coupled_util.hpp"

using namespace coloc;

namespace {

std::vector<double> globalPressure(coupling::Simulation& sim) {
  return test::globalCellValues(sim, sim.fluid()->fields().p);
}

}  // namespace

TEST(Case1Outflow, ParticleLeavesSameStepOnEveryRankCount) {
  const Comm world = Comm::world();
  const test::SelfComm selfComm;
  const Comm self = selfComm.comm();
  // started at x = 0.65 m (a third of a metre from the outlet: it crosses the block faces at
  // 0.75 m on 4 ranks) so that the test stays short
  const std::vector<std::string> over = {
      "run.end_time=0.6", "run.progress_interval_s=0", "fluid.pressure.tol=1e-13",
      "particles.sources.0.positions=[0.65,0.1,0.1]", "particles.boundary.xhi=outflow"};
  const std::string path = COLOC_SOURCE_DIR "/bench/cases/case1.json";
  {
    const Config cfg = Config::load(world, path, over, coupling::caseSchema());
    coupling::Simulation par(world, cfg);
    coupling::Simulation ser(self, cfg);
    const double r = cfg.at("particles.sources")[0]["radius"].get<double>();
    const double vp = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    const double mp = 1000.0 * vp;
    long long leftPar = -1, leftSer = -1;
    double lastX = 0;
    while (!par.finished()) {
      par.step();
      ser.step();
      const auto a = test::particleState(par, 0), b = test::particleState(ser, 0);
      if (!a.found && leftPar < 0) leftPar = par.steps();
      if (!b.found && leftSer < 0) leftSer = ser.steps();
      ASSERT_EQ(a.found, b.found) << "step " << par.steps();
      if (a.found) {
        for (int d = 0; d < 3; ++d) {
          ASSERT_NEAR(a.x[d], b.x[d], 1e-10 * std::abs(b.x[0])) << "step " << par.steps();
          ASSERT_NEAR(a.v[d], b.v[d], 1e-10 * (std::abs(b.v[0]) + 1e-30)) << "step " << par.steps();
          ASSERT_NEAR(a.f[d], b.f[d], 1e-10 * (std::abs(b.f[0]) + 1e-30)) << "step " << par.steps();
        }
        ASSERT_NEAR(par.depositedSolidVolume(), vp, 1e-12 * vp) << "step " << par.steps();
        lastX = a.x[0];
      } else if (par.steps() > leftPar) {  // the deposit of the step it left still held it
        ASSERT_EQ(par.depositedSolidVolume(), 0.0) << "step " << par.steps();
      }
    }
    // it left, through the outlet, at the same step, and well before the end
    ASSERT_GT(leftPar, 0) << "the particle never left";
    EXPECT_EQ(leftPar, leftSer);
    EXPECT_LT(leftPar, par.steps() - 10);
    EXPECT_GT(lastX, 1.0 - 0.05);  // last seen within a cell of the outlet face
    if (world.isRoot())
      std::printf("case1 outflow: left at fluid step %lld (t = %.4f s), last x = %.6f m\n", leftPar,
                  leftPar * 0.005, lastX);
    const Json dp = par.particles()->diagnostics(), ds = ser.particles()->diagnostics();
    for (const Json* d : {&dp, &ds}) {
      EXPECT_EQ((*d)["count"].get<long long>(), 0);
      EXPECT_EQ((*d)["count_initial"].get<long long>(), 1);
      EXPECT_EQ((*d)["count_out"].get<long long>(), 1);
      EXPECT_EQ((*d)["count_in"].get<long long>(), 0);
      EXPECT_EQ((*d)["count_out_by_face"]["xhi"].get<long long>(), 1);
      EXPECT_NEAR((*d)["mass_out"].get<double>(), mp, 1e-15 * mp);
      EXPECT_EQ((*d)["mass_held"].get<double>(), 0.0);
      EXPECT_LE((*d)["mass_balance"].get<double>(), 1e-15);
    }
    const auto pp = globalPressure(par), ps = globalPressure(ser);
    double scale = 0;
    for (double v : ps) scale = std::max(scale, std::abs(v));
    for (std::size_t c = 0; c < pp.size(); ++c) ASSERT_NEAR(pp[c], ps[c], 1e-10 * scale) << c;
    EXPECT_LE(par.momentumBalance(), 1e-12);
  }
}

TEST(Case1Outflow, WallOutletKeepsTheParticle) {
  // the default (wall on the non-periodic xhi face): the particle stays, as before
  const std::vector<std::string> over = {"run.end_time=0.6", "run.progress_interval_s=0",
                                         "particles.sources.0.positions=[0.65,0.1,0.1]"};
  const Config cfg = Config::load(Comm::world(), COLOC_SOURCE_DIR "/bench/cases/case1.json", over,
                                  coupling::caseSchema());
  coupling::Simulation sim(Comm::world(), cfg);
  while (!sim.finished()) sim.step();
  const Json d = sim.particles()->diagnostics();
  EXPECT_EQ(d["count"].get<long long>(), 1);
  EXPECT_EQ(d["count_out"].get<long long>(), 0);
  EXPECT_LE(d["mass_balance"].get<double>(), 1e-15);
}
