// The particle field table survives an in-memory re-balance: extra per-particle quantities (one
// table entry each, ParticleStore::addField) carried by the particles of a coupled run keep their
// values when coupling's applyRebalance moves the run onto other blocks (the DemState carries
// the named extra columns through the CommPlan redistribution; the restoring DemSolver registers
// them), and keep travelling with their particles afterwards.
#include <gtest/gtest.h>

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
