// Re-balancing in memory against the former path through a checkpoint file: two runs of the same
// case move onto the same new blocks after 10 steps, one in memory (applyRebalance), one through
// HDF5 (applyRebalanceThroughFile). Right after the move every particle (by id), every contact
// history and the owned fluid fields are the same bit for bit; after 10 more steps the particles
// agree to round-off (the order of the particles on a rank may differ: a few sums change order).
#include <unistd.h>

#include <filesystem>

#include "coloc/coupling/rebalance.hpp"
#include "coloc/partition/setup.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

constexpr int kCount = 400;

const std::string kCase = test::settlingBedCase(kCount, 20);

std::vector<double> trajectories(coupling::Simulation& sim) {
  std::vector<double> s(9 * kCount, 0.0);
  const auto& p = sim.particles()->particles();
  for (std::size_t i = 0; i < p.nOwned; ++i)
    for (int d = 0; d < 3; ++d) {
      const auto k = 9 * static_cast<std::size_t>(p.id[i]) + static_cast<std::size_t>(d);
      s[k] = p.x[d][i];
      s[k + 3] = p.v[d][i];
      s[k + 6] = p.fExt[d][i];
    }
  sim.decomposition().comm().sumInPlace(std::span<double>(s));
  return s;
}

std::vector<double> histories(coupling::Simulation& sim) {
  std::vector<double> h(3 * kCount * kCount, 0.0);
  const dem::DemState s = sim.particles()->saveState();
  for (const auto& c : s.contacts)
    for (int d = 0; d < 3; ++d)
      h[3 * static_cast<std::size_t>(c.holder * kCount + c.partner) + static_cast<std::size_t>(d)] =
          c.shear[static_cast<std::size_t>(d)];
  sim.decomposition().comm().sumInPlace(std::span<double>(h));
  return h;
}

/// Owned fluid values by global cell (p, eps, u_z, K): the same layout on any blocks.
std::vector<double> fluidValues(coupling::Simulation& sim) {
  const auto& dec = sim.decomposition();
  const auto& g = dec.grid();
  std::vector<double> v(4 * static_cast<std::size_t>(g.cellCount()), 0.0);
  const auto& f = sim.fluid()->fields();
  const Int3 lo = dec.lo();
  forEach(f.p.interior(), [&](int i, int j, int k) {
    const auto c = static_cast<std::size_t>((lo[0] + i) +
                                            g.cells[0] * ((lo[1] + j) + g.cells[1] * (lo[2] + k)));
    v[4 * c] = f.p(i, j, k);
    v[4 * c + 1] = f.eps(i, j, k);
    v[4 * c + 2] = f.u[2](i, j, k);
    v[4 * c + 3] = f.K(i, j, k);
  });
  dec.comm().sumInPlace(std::span<double>(v));
  return v;
}

}  // namespace

TEST(RebalanceInMemory, SameStateAsThroughTheFile) {
  const Comm world = Comm::world();
  const Config cfg = test::caseFromText(kCase);
  const std::string scratch =
      world.broadcast((std::filesystem::temp_directory_path() /
                       ("coloc_rebalance_mem_" + std::to_string(::getpid()) + ".h5"))
                          .string());
  const auto even = [&] {
    return coupling::Layouts{
        decompositionFromConfig(world, cfg), std::nullopt, "balanced", CostModel{}, 1.0, 1.0};
  };
  auto a = std::make_unique<coupling::Simulation>(cfg, even());
  auto b = std::make_unique<coupling::Simulation>(cfg, even());
  for (int s = 0; s < 10; ++s) {
    a->step();
    b->step();
  }
  ASSERT_EQ(trajectories(*a), trajectories(*b));
  // The layouts first: the call takes the pointer by value.
  coupling::Layouts la = test::shiftedLayouts(a->decomposition()),
                    lb = test::shiftedLayouts(b->decomposition());
  a = coupling::applyRebalance(std::move(a), cfg, std::move(la));
  b = coupling::applyRebalanceThroughFile(std::move(b), cfg, std::move(lb), scratch);
  EXPECT_FALSE(std::filesystem::exists(scratch));
  EXPECT_EQ(a->decomposition().cuts(), b->decomposition().cuts());
  EXPECT_EQ(a->steps(), b->steps());
  EXPECT_EQ(a->time(), b->time());
  EXPECT_EQ(a->demSubsteps(), b->demSubsteps());
  EXPECT_EQ(trajectories(*a), trajectories(*b));
  EXPECT_EQ(histories(*a), histories(*b));
  EXPECT_EQ(fluidValues(*a), fluidValues(*b));
  while (!a->finished()) {
    a->step();
    b->step();
  }
  ASSERT_TRUE(b->finished());
  const auto ta = trajectories(*a), tb = trajectories(*b);
  double scale[3] = {0, 0, 0};
  for (std::size_t k = 0; k < tb.size(); ++k)
    scale[k % 9 / 3] = std::max(scale[k % 9 / 3], std::abs(tb[k]));
  for (std::size_t k = 0; k < ta.size(); ++k)
    ASSERT_NEAR(ta[k], tb[k], 1e-10 * scale[k % 9 / 3]) << "particle " << k / 9;
  const auto fa = fluidValues(*a), fb = fluidValues(*b);
  double fs[4] = {0, 0, 0, 0};
  for (std::size_t k = 0; k < fb.size(); ++k) fs[k % 4] = std::max(fs[k % 4], std::abs(fb[k]));
  for (std::size_t k = 0; k < fa.size(); ++k)
    ASSERT_NEAR(fa[k], fb[k], 1e-10 * fs[k % 4]) << "cell " << k / 4;
}
