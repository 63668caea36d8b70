// run.timer_sync: timed barriers at the solvers' sync points (the fluid's halo after the momentum
// predictor, the DEM's rebuild vote in every sub-step) book the wait for the slowest rank to
// `sync`. They change no result (every particle's position and velocity bit-identical to the run
// without them), and they are reached by every rank the same number of times: one a fluid step
// and one a DEM sub-step beyond the two barriers every coupled step has (none on one rank).
#include <vector>

#include "coupled_util.hpp"

using namespace coloc;

namespace {

constexpr int kCount = 300;

// Every particle's position and velocity by global id (ids 0 .. kCount-1), on every rank.
std::vector<double> states(coupling::Simulation& sim) {
  const auto& p = sim.particles()->particles();
  std::vector<double> all(6 * kCount, 0.0);
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    const auto id = static_cast<std::size_t>(p.id[i]);
    EXPECT_LT(id, static_cast<std::size_t>(kCount));
    if (id >= static_cast<std::size_t>(kCount)) continue;
    for (int d = 0; d < 3; ++d) {
      all[6 * id + d] = p.x[d][i];
      all[6 * id + 3 + d] = p.v[d][i];
    }
  }
  sim.decomposition().comm().sumInPlace(std::span<double>(all));
  return all;
}

TEST(TimerSync, BooksTheWaitAndChangesNoResult) {
  constexpr int kSteps = 3;
  const std::string text = test::settlingBedCase(kCount, kSteps);
  std::vector<double> result[2];
  long long syncCalls[2] = {0, 0}, substeps = 0;
  for (int on = 0; on < 2; ++on) {
    const Config cfg =
        test::caseFromText(text, {std::string("run.timer_sync=") + (on ? "true" : "false")});
    coupling::Simulation sim(Comm::world(), cfg);
    sim.beginRun();
    while (!sim.finished()) sim.step();
    result[on] = states(sim);
    syncCalls[on] = sim.timers().calls(Phase::Sync);
    substeps = sim.demSubsteps();
  }
  EXPECT_GT(substeps, kSteps);
  // bit for bit: every position and velocity (a sum over ranks of one non-zero term each)
  EXPECT_TRUE(result[0] == result[1]) << "a timed barrier changed the particles";
  const int ranks = Comm::world().size();
  if (ranks == 1) {
    EXPECT_EQ(syncCalls[0], 0);
    EXPECT_EQ(syncCalls[1], 0);
  } else {
    EXPECT_EQ(syncCalls[0], 2 * kSteps);
    EXPECT_EQ(syncCalls[1], 2 * kSteps + kSteps + substeps);
  }
}

}  // namespace
