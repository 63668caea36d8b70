// Balanced co-located blocks: separable cuts from a cost model.
#include <gtest/gtest.h>

#include "coloc/partition/balance.hpp"

using namespace coloc;

namespace {

/// The clustered case: the case-3 box with a particle bed in its lowest fifth (along z).
std::vector<double> clusteredCost(const GlobalGrid& g, double perCell, double perParticleCell) {
  std::vector<double> c(static_cast<std::size_t>(g.cellCount()), perCell);
  for (int k = 0; k < g.cells[2] / 5; ++k)
    for (int j = 0; j < g.cells[1]; ++j)
      for (int i = 0; i < g.cells[0]; ++i)
        c[static_cast<std::size_t>(i + g.cells[0] * (j + g.cells[1] * k))] += perParticleCell;
  return c;
}

GlobalGrid box() {
  GlobalGrid g;
  g.length = {0.48, 0.04, 0.48};
  g.cells = {48, 4, 48};
  return g;
}

}  // namespace

TEST(Balance, UniformCostGivesEvenCuts) {
  const auto g = box();
  const std::vector<double> cost(static_cast<std::size_t>(g.cellCount()), 1.0);
  const auto l = balanceBlocks(g, cost, 4, 2, 1);
  EXPECT_NEAR(l.imbalance(), 1.0, 1e-12);
}

TEST(Balance, ClusteredBedIsBalancedWithinFifteenPercent) {
  const auto g = box();
  // 10 particles per bed cell at 20x the cost of a cell: most of the work is in the bed.
  const auto cost = clusteredCost(g, 1.0, 200.0);
  for (int ranks : {2, 4, 8}) {
    const auto bal = balanceBlocks(g, cost, ranks, 2, 1);
    // The uniform strategy's layout: its own process grid, even cuts.
    BalancedLayout uni;
    uni.dims = Decomposition::chooseDims(ranks, g);
    for (int d = 0; d < 3; ++d) uni.cuts[d] = Decomposition::evenCuts(g.cells[d], uni.dims[d]);
    evaluateLayout(g, cost, uni);
    const double bestUniform = uni.maxBlockCost;
    EXPECT_LE(bal.imbalance(), 1.15) << ranks << " ranks";
    if (ranks >= 4) {
      EXPECT_GE(bestUniform / bal.maxBlockCost, 1.5) << ranks << " ranks";
    }
    for (int d = 0; d < 3; ++d) {
      ASSERT_EQ(bal.cuts[d].front(), 0);
      ASSERT_EQ(bal.cuts[d].back(), g.cells[d]);
      for (std::size_t i = 1; i < bal.cuts[d].size(); ++i)
        ASSERT_GE(bal.cuts[d][i] - bal.cuts[d][i - 1], 2);
    }
  }
}

TEST(Balance, CutsRespectTheBinGranularity) {
  const auto g = box();
  const auto cost = clusteredCost(g, 1.0, 50.0);
  const auto l = balanceBlocks(g, cost, 4, 3, 3);
  for (int d = 0; d < 3; ++d)
    for (std::size_t i = 1; i + 1 < l.cuts[d].size(); ++i) EXPECT_EQ(l.cuts[d][i] % 3, 0);
}

TEST(Balance, CellCostsCountParticlesOnEveryRank) {
  GlobalGrid g = box();
  const auto dec = Decomposition::uniform(Comm::world(), g);
  // Rank r contributes r+1 particles in cell (1,1,1).
  std::vector<double> x(static_cast<std::size_t>(dec.rank() + 1), 0.015), y(x.size(), 0.015),
      z(x.size(), 0.015);
  const auto c = cellCosts(dec, x, y, z, {0.5, 2.0});
  const int n = dec.size();
  EXPECT_DOUBLE_EQ(c[static_cast<std::size_t>(1 + 48 * (1 + 4 * 1))], 0.5 + 2.0 * n * (n + 1) / 2);
  EXPECT_DOUBLE_EQ(c[0], 0.5);
}

TEST(Balance, CellCostsOnRootEqualCellCostsWithoutAGlobalCollective) {
  GlobalGrid g = box();
  const auto dec = Decomposition::uniform(Comm::world(), g);
  // Particles inside this rank's block, spread over its cells, and (rank r) r+1 particles in
  // cell (1,1,1), which lies outside the block of every rank but the first: the sparse path.
  std::vector<double> x, y, z;
  const auto lo = dec.blockLo(), hi = dec.blockHi();
  for (int p = 0; p < 500; ++p) {
    x.push_back(lo[0] + (hi[0] - lo[0]) * ((p * 37) % 101) / 101.0);
    y.push_back(lo[1] + (hi[1] - lo[1]) * ((p * 53) % 97) / 97.0);
    z.push_back(lo[2] + (hi[2] - lo[2]) * ((p * 71) % 89) / 89.0);
  }
  for (int p = 0; p <= dec.rank(); ++p) {
    x.push_back(0.015);
    y.push_back(0.015);
    z.push_back(0.015);
  }
  const auto all = cellCosts(dec, x, y, z, {0.5, 2.0});
  const auto root = cellCostsOnRoot(dec, x, y, z, {0.5, 2.0});
  if (dec.rank() != 0) {
    EXPECT_TRUE(root.empty());
    return;
  }
  ASSERT_EQ(root.size(), all.size());
  for (std::size_t c = 0; c < all.size(); ++c) ASSERT_EQ(root[c], all[c]) << "cell " << c;
}
