// The riser of bench/cases/riser.json, shortened to 80 mm (16 cells) and 0.6 s: beads fed
// through a patch of the bottom face at 2000/s, carried up by the water and removed at the top
// (outflow). The number of beads in the column levels off: the last four samples (every 0.05 s)
// within 5 % of their mean, beads have left through zhi, the inflow kept its rate, and
// mass initial + in = out + held to 1e-13. One rank (the parallel paths of inflow and outflow
// are compared with serial runs in tests/dem/test_flow.cpp and test_coupled_outflow.cpp).
#include <cmath>
#include <cstdio>

#include "coupled_util.hpp"

using namespace coloc;

TEST(Riser, ReachesSteadyCount) {
  const Comm world = Comm::world();
  // softer beads (E = 1.6e5 Pa) allow a DEM step of 5e-5 s: 20 sub-steps per fluid step
  const std::vector<std::string> over = {"domain.length=[0.02,0.02,0.08]",
                                         "domain.cells=[4,4,16]",
                                         "run.end_time=0.6",
                                         "run.progress_interval_s=0",
                                         "particles.materials.0.young=1.6e5",
                                         "particles.dt=5e-5"};
  const Config cfg =
      Config::load(world, COLOC_SOURCE_DIR "/bench/cases/riser.json", over, coupling::caseSchema());
  coupling::Simulation sim(world, cfg);
  std::vector<long long> counts;
  while (!sim.finished()) {
    sim.step();
    if (sim.steps() % 50 == 0) counts.push_back(sim.particles()->globalCount());
  }
  const Json d = sim.particles()->diagnostics();
  if (world.isRoot()) {
    std::printf("riser (80 mm), ranks %d: count every 0.05 s:", world.size());
    for (auto c : counts) std::printf(" %lld", c);
    std::printf(
        "\n  in %lld, out %lld (zhi %lld), waiting %lld, mass in %.4e out %.4e held "
        "%.4e, balance %.1e\n",
        d["count_in"].get<long long>(), d["count_out"].get<long long>(),
        d["count_out_by_face"]["zhi"].get<long long>(), d["inflow_waiting"].get<long long>(),
        d["mass_in"].get<double>(), d["mass_out"].get<double>(), d["mass_held"].get<double>(),
        d["mass_balance"].get<double>());
  }
  ASSERT_EQ(counts.size(), 12u);
  const double mean = (counts[8] + counts[9] + counts[10] + counts[11]) / 4.0;
  for (std::size_t k = 8; k < 12; ++k) EXPECT_NEAR(counts[k], mean, 0.05 * mean) << k;
  EXPECT_GT(counts[11], counts[3]);  // it filled first
  EXPECT_GT(d["count_out"].get<long long>(), 300);
  EXPECT_EQ(d["count_out_by_face"]["zhi"], d["count_out"]);
  // 2000/s: floor(2000 t) due at the start of the last DEM sub-step (t = 0.6 - 5e-5 s)
  EXPECT_EQ(d["count_in"].get<long long>() + d["inflow_waiting"].get<long long>(), 1199);
  EXPECT_EQ(d["inflow_waiting"].get<long long>(), 0);
  EXPECT_LE(d["mass_balance"].get<double>(), 1e-13);
}
