// The particle field table survives an in-memory re-balance: extra per-particle quantities (one
// table entry each, ParticleStore::addField) carried by the particles of a coupled run keep their
// values when coupling's applyRebalance moves the run onto other blocks (the DemState carries
// the named extra columns through the CommPlan redistribution; the restoring DemSolver registers
// them), and keep travelling with their particles afterwards. With particles.heat, the particles'
// energy accounts (particles.heat.*) go through the same re-balance: every account unchanged (the
// enthalpy to round-off of its sum), and the balance closes to 1e-12 at the end.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "coloc/coupling/rebalance.hpp"
#include "coloc/coupling/simulation.hpp"
#include "coloc/dem/fields.hpp"
#include "coloc/partition/setup.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

const std::string kCase = test::settlingBedCase(400, 16);

/// Particles (owned, and ghosts for the fields that reach them) whose extra values are not
/// those set from their id.
long wrong(const dem::ParticleStore& p) {
  long bad = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.field("tag")[i] != 3.0 * static_cast<double>(p.id[i]) + 0.5) ++bad;
    if (i < p.nOwned)
      for (int k = 0; k < 3; ++k)
        if (p.field("pair", k)[i] != static_cast<double>(k + 1) * static_cast<double>(p.id[i]))
          ++bad;
  }
  return bad;
}

}  // namespace

TEST(ParticleFields, SurviveInMemoryRebalance) {
  const Comm world = Comm::world();
  const Config cfg = test::caseFromText(kCase);
  auto sim = std::make_unique<coupling::Simulation>(
      cfg, coupling::Layouts{decompositionFromConfig(world, cfg), std::nullopt, "balanced",
                             CostModel{}, 1.0, 1.0});
  {
    auto& p = sim->particles()->particles();
    p.addField("tag", 1, dem::kOpGhostBuild | dem::kOpMigrate | dem::kOpState);
    p.addField("pair", 3, dem::kOpMigrate | dem::kOpState);
    for (std::size_t i = 0; i < p.nOwned; ++i) {
      p.field("tag")[i] = 3.0 * static_cast<double>(p.id[i]) + 0.5;
      for (int k = 0; k < 3; ++k)
        p.field("pair", k)[i] = static_cast<double>(k + 1) * static_cast<double>(p.id[i]);
    }
  }
  for (int s = 0; s < 8; ++s) sim->step();
  ASSERT_EQ(world.sum(wrong(sim->particles()->particles())), 0);
  const long long count = sim->particles()->globalCount();
  coupling::Layouts to = test::shiftedLayouts(sim->decomposition());
  const auto cutsBefore = sim->decomposition().cuts();
  sim = coupling::applyRebalance(std::move(sim), cfg, std::move(to));
  if (world.size() > 1) {
    EXPECT_NE(sim->decomposition().cuts(), cutsBefore);
  }
  const auto& q = sim->particles()->particles();
  ASSERT_EQ(q.extra.size(), 2u);
  EXPECT_EQ(q.extra[0].name, "tag");
  EXPECT_EQ(q.extra[1].name, "pair");
  EXPECT_EQ(q.extra[1].components, 3);
  EXPECT_EQ(sim->particles()->globalCount(), count);
  EXPECT_EQ(world.sum(wrong(q)), 0);
  while (!sim->finished()) sim->step();
  EXPECT_EQ(world.sum(wrong(sim->particles()->particles())), 0);
  EXPECT_EQ(sim->particles()->globalCount(), count);
}

TEST(ParticleHeat, AccountsSurviveInMemoryRebalance) {
  const Comm world = Comm::world();
  // the settling bed with particle heat, walls at 350 K, re-balanced at step 20 of 40
  std::string text = test::settlingBedCase(400, 40);
  text.replace(text.find("\"dt\": 5e-5,"), 12,
               "\"dt\": 5e-5, \"heat\": true, \"wall_temperature\": 350,");
  text.replace(text.find("\"friction\": 0.5 }"), 18,
               "\"friction\": 0.5, \"heat_capacity\": 800, \"conductivity\": 1 }");
  const Config cfg = test::caseFromText(text);
  auto sim = std::make_unique<coupling::Simulation>(
      cfg, coupling::Layouts{decompositionFromConfig(world, cfg), std::nullopt, "balanced",
                             CostModel{}, 1.0, 1.0});
  for (int s = 0; s < 20; ++s) sim->step();
  const Json before = sim->particles()->diagnostics()["heat"];
  coupling::Layouts to = test::shiftedLayouts(sim->decomposition());
  sim = coupling::applyRebalance(std::move(sim), cfg, std::move(to));
  const Json after = sim->particles()->diagnostics()["heat"];
  for (const char* k : {"enthalpy_initial", "wall_heat_in", "ext_heat_in", "inflow_enthalpy_in",
                        "outflow_enthalpy_out"})
    EXPECT_EQ(after[k].get<double>(), before[k].get<double>()) << k;
  const double H = before["enthalpy"].get<double>();
  EXPECT_NEAR(after["enthalpy"].get<double>(), H, 1e-14 * H);
  while (!sim->finished()) sim->step();
  const Json end = sim->particles()->diagnostics()["heat"];
  if (world.isRoot())
    std::printf(
        "re-balance with heat, %d ranks: wall heat %.4e J before, %.4e J at the end; "
        "balance %.2e\n",
        world.size(), before["wall_heat_in"].get<double>(), end["wall_heat_in"].get<double>(),
        end["energy_balance"].get<double>());
  EXPECT_NE(end["wall_heat_in"].get<double>(), 0.0);  // the bed reached the floor
  EXPECT_LE(end["energy_balance"].get<double>(), 1e-12);
}
