// `coloc plan` on the tiled strategy: the boxes tile the grid, every cell and particle is owned
// once, and the halo traffic the plan predicts per rank (the fluid's gathers, the reverse sum of
// the deposits) equals what BoxHaloPlan books on that layout, rank by rank. (The tiled strategy
// has no run yet: the DEM ghosts of the plan are not checked against one.)
#include <gtest/gtest.h>

#include <string>

#include "coloc/coupling/plan.hpp"
#include "coloc/partition/box_halo.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

// A layered bed in a closed box (test_plan_exact's), and a box periodic along x.
const char* const kBed = test::kLayeredBedCase;

const char* const kPeriodic = test::kPeriodicSuspensionCase;

class PlanTiled : public ::testing::TestWithParam<const char*> {};

}  // namespace

TEST_P(PlanTiled, BoxesTileAndHaloTrafficEqualsTheBoxPlan) {
  const Comm world = Comm::world();
  const Config cfg = test::caseFromText(GetParam(), {});
  const coupling::PlanCase pc = coupling::planCase(cfg);
  const coupling::LayoutPlan plan = coupling::planLayout(pc, "tiled", world.size());
  ASSERT_TRUE(plan.error.empty()) << plan.error;
  ASSERT_EQ(plan.boxes.size(), static_cast<std::size_t>(world.size()));
  BoxLayout L;
  L.grid = pc.grid;
  L.box = plan.boxes;
  EXPECT_NO_THROW(L.ownerMap());
  long long cells = 0, parts = 0;
  for (const auto& R : plan.rank) cells += R.cells, parts += R.particles;
  EXPECT_EQ(cells, pc.grid.cellCount());
  EXPECT_EQ(parts, static_cast<long long>(pc.particles.x[0].size()));
  EXPECT_GE(plan.imbalance, 1.0);
  EXPECT_LE(plan.imbalanceFloor, plan.imbalance + 1e-12);

  // The step's halo schedule (coupling/src/plan.cpp) on BoxHaloPlans of this rank's box.
  const int me = world.rank();
  const IndexBox& b = L.box[static_cast<std::size_t>(me)];
  const Int3 n{b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]};
  Timers timers;
  const auto gather = [&](FieldLayout layout, int fields) {
    std::vector<Field3<double>> f(static_cast<std::size_t>(fields), Field3<double>(layout));
    std::vector<Field3<double>*> p;
    for (auto& x : f) p.push_back(&x);
    BoxHaloPlan(world, L, layout).gather(p, &timers, Exchange::IntraPhysics, Traffic::FluidHalo);
  };
  gather({n, 2, {0, 0, 0}}, 6);
  gather({n, 2, {0, 0, 0}}, 1);
  for (int c = 0; c < 3; ++c)
    for (int t = 0; t < 3; ++t) gather({n, 2, {c == 0, c == 1, c == 2}}, 1);
  gather({n, 2, {0, 0, 0}}, 3);
  {
    const FieldLayout one{n, 1, {0, 0, 0}};
    std::vector<Field3<double>> f(5, Field3<double>(one));
    std::vector<Field3<double>*> p;
    for (auto& x : f) p.push_back(&x);
    BoxHaloPlan(world, L, one).scatterSum(p, Fold::Mirror, &timers);
  }
  const auto& R = plan.rank[static_cast<std::size_t>(me)];
  for (Traffic t : {Traffic::FluidHalo, Traffic::DepositSum}) {
    const auto k = static_cast<std::size_t>(t);
    EXPECT_EQ(R.perStep[k].bytes, timers.bytes(t)) << "rank " << me << " " << kTrafficNames[k];
    EXPECT_EQ(R.perStep[k].messages, timers.messages(t))
        << "rank " << me << " " << kTrafficNames[k];
  }
  if (world.size() > 1) {
    EXPECT_GT(world.sum(timers.bytes(Traffic::DepositSum)), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, PlanTiled, ::testing::Values(kBed, kPeriodic));
