// Tiled co-located layouts (recursive coordinate bisection): every cell owned exactly once for
// any rank count, legal box widths and cut planes, balance on analytic clustered cost fields.
#include <gtest/gtest.h>

#include <cmath>

#include "coloc/core/error.hpp"
#include "coloc/partition/balance.hpp"
#include "coloc/partition/tiled.hpp"

using namespace coloc;

namespace {

std::size_t at(const GlobalGrid& g, int i, int j, int k) {
  return static_cast<std::size_t>(i + g.cells[0] * (j + g.cells[1] * k));
}

/// The clustered case: a bed in the lowest fifth along z, `bed` extra cost per bed cell.
std::vector<double> bedCost(const GlobalGrid& g, double bed) {
  std::vector<double> c(static_cast<std::size_t>(g.cellCount()), 1.0);
  for (int k = 0; k < g.cells[2] / 5; ++k)
    for (int j = 0; j < g.cells[1]; ++j)
      for (int i = 0; i < g.cells[0]; ++i) c[at(g, i, j, k)] += bed;
  return c;
}

/// Work clustered in two directions: a Gaussian blob in a corner of the x-z plane.
std::vector<double> cornerBlob(const GlobalGrid& g, double peak) {
  std::vector<double> c(static_cast<std::size_t>(g.cellCount()), 1.0);
  for (int k = 0; k < g.cells[2]; ++k)
    for (int j = 0; j < g.cells[1]; ++j)
      for (int i = 0; i < g.cells[0]; ++i) {
        const double x = (i + 0.5) / g.cells[0], z = (k + 0.5) / g.cells[2];
        c[at(g, i, j, k)] +=
            peak * std::exp(-((x - 0.2) * (x - 0.2) + (z - 0.25) * (z - 0.25)) / (2 * 0.1 * 0.1));
      }
  return c;
}

GlobalGrid clusteredBox() {
  GlobalGrid g;
  g.length = {0.48, 0.04, 0.48};
  g.cells = {48, 4, 48};
  return g;
}

/// Every cell once, widths >= minCells (or the whole axis), bounds on the granularity.
void checkLayout(const TiledLayout& l, int ranks, const TiledOptions& opt) {
  const auto& g = l.layout.grid;
  ASSERT_EQ(l.layout.size(), ranks);
  const auto owner = l.layout.ownerMap();  // throws on a cell owned twice or never
  ASSERT_EQ(owner.size(), static_cast<std::size_t>(g.cellCount()));
  for (const auto& b : l.layout.box)
    for (int d = 0; d < 3; ++d) {
      ASSERT_GE(b.hi[d] - b.lo[d], std::min(opt.minCells, g.cells[d]));
      for (int c : {b.lo[d], b.hi[d]})
        ASSERT_TRUE(c % opt.granularity == 0 || c == g.cells[d]) << c;
    }
}

}  // namespace

TEST(Tiled, EveryCellOnceForEveryRankCountUpTo256AndPrimesTo1021) {
  GlobalGrid g;
  g.cells = {40, 24, 36};  // capacity 20 x 12 x 18 boxes of 2 cells
  const auto cost = cornerBlob(g, 50.0);
  const TiledOptions opt;
  std::vector<int> counts;
  for (int p = 1; p <= 256; ++p) counts.push_back(p);
  for (int p : {257, 509, 512, 521, 769, 1000, 1021, 1024}) counts.push_back(p);
  for (const int p : counts) {
    const auto l = tiledBoxes(g, cost, p, opt);
    checkLayout(l, p, opt);
    if (HasFatalFailure()) FAIL() << p << " ranks";
  }
}

TEST(Tiled, PrimesOnSizesThatDoNotDivideWithGranularity) {
  GlobalGrid g;
  g.cells = {31, 17, 23};
  g.periodic = {true, false, true};
  const auto cost = bedCost(g, 30.0);
  TiledOptions opt;
  opt.granularity = 3;
  opt.minCells = 2;
  for (int p : {1, 2, 3, 5, 7, 11, 13, 29, 31, 37, 53, 97}) {
    const auto l = tiledBoxes(g, cost, p, opt);
    checkLayout(l, p, opt);
    if (HasFatalFailure()) FAIL() << p << " ranks";
  }
}

TEST(Tiled, TightCapacityTakesTheSplitThatFitsAndRefusesBeyond) {
  GlobalGrid g;
  g.cells = {6, 6, 2};  // exactly 3 x 3 x 1 boxes of 2 cells
  const std::vector<double> cost(static_cast<std::size_t>(g.cellCount()), 1.0);
  const auto l = tiledBoxes(g, cost, 9, {});
  checkLayout(l, 9, {});
  EXPECT_NEAR(l.imbalance(), 1.0, 1e-12);
  EXPECT_THROW(tiledBoxes(g, cost, 10, {}), ConfigError);
  // A grid thinner than the ghost width along an axis keeps that axis whole.
  GlobalGrid thin;
  thin.cells = {16, 1, 8};
  const std::vector<double> c1(static_cast<std::size_t>(thin.cellCount()), 1.0);
  checkLayout(tiledBoxes(thin, c1, 32, {}), 32, {});
}

TEST(Tiled, UniformCostIsBalanced) {
  GlobalGrid g;
  g.cells = {64, 32, 32};
  const std::vector<double> cost(static_cast<std::size_t>(g.cellCount()), 1.0);
  for (int p : {2, 4, 8, 16, 64})
    EXPECT_NEAR(tiledBoxes(g, cost, p, {}).imbalance(), 1.0, 1e-12) << p;
  for (int p : {3, 5, 7, 12})  // the bisection tree is not a power of two: a few percent
    EXPECT_LE(tiledBoxes(g, cost, p, {}).imbalance(), 1.05) << p;
}

TEST(Tiled, ClusteredBedBeatsSeparableCutsAndUniform) {
  const auto g = clusteredBox();
  const auto cost = bedCost(g, 200.0);
  for (int p : {4, 8}) {
    const auto t = tiledBoxes(g, cost, p, {});
    checkLayout(t, p, {});
    const auto bal = balanceBlocks(g, cost, p, 2, 1);
    BalancedLayout uni;
    uni.dims = Decomposition::chooseDims(p, g);
    for (int d = 0; d < 3; ++d) uni.cuts[d] = Decomposition::evenCuts(g.cells[d], uni.dims[d]);
    evaluateLayout(g, cost, uni);
    EXPECT_LE(t.imbalance(), 1.05) << p;
    EXPECT_LE(t.maxCost, bal.maxBlockCost * (1 + 1e-12)) << p;
    EXPECT_GE(uni.maxBlockCost / t.maxCost, p == 8 ? 1.6 : 1.5) << p;
  }
}

TEST(Tiled, WorkClusteredInTwoDirections) {
  // A blob a few cells wide: one layer of cells in it is a large share of a box's cost, so the
  // whole-cell cuts of both strategies leave some imbalance; the boxes follow the blob, the
  // separable cuts cannot (at 64 ranks: 1.10 against 1.23).
  GlobalGrid g;
  g.cells = {64, 8, 64};
  const auto cost = cornerBlob(g, 200.0);
  for (int p : {8, 16, 64}) {
    const auto t = tiledBoxes(g, cost, p, {});
    const auto bal = balanceBlocks(g, cost, p, 2, 1);
    EXPECT_LE(t.imbalance(), p == 64 ? 1.10 : 1.07) << p;
    EXPECT_LE(t.maxCost, bal.maxBlockCost * (p == 64 ? 0.9 : 1 + 1e-9))
        << p << " ranks: balanced " << bal.imbalance() << ", tiled " << t.imbalance();
  }
}

TEST(Tiled, SurfaceTermCountsHaloCellsAndBalancesThem) {
  GlobalGrid g;
  g.cells = {10, 10, 10};
  // Interior box 2..5: (4+4)^3 - 4^3; at the low wall only the high side counts.
  EXPECT_EQ(haloCells(g, {{2, 2, 2}, {6, 6, 6}}, 2), 8LL * 8 * 8 - 64);
  EXPECT_EQ(haloCells(g, {{0, 0, 0}, {10, 10, 10}}, 2), 0);
  EXPECT_EQ(haloCells(g, {{0, 0, 0}, {5, 10, 10}}, 2), 2LL * 10 * 10);
  g.periodic = {true, true, true};
  EXPECT_EQ(haloCells(g, {{0, 0, 0}, {10, 10, 10}}, 1), 12LL * 12 * 12 - 1000);
  g.periodic = {false, false, false};
  g.cells = {60, 20, 20};
  const std::vector<double> cost(static_cast<std::size_t>(g.cellCount()), 1.0);
  TiledOptions opt;
  opt.surfaceCost = 2.0;
  const auto l = tiledBoxes(g, cost, 3, opt);
  // Three slabs along x: the middle one has two cut faces, the last one; the second cut, made
  // knowing both, makes the middle slab thinner. (The first cut cannot know the cut its right
  // side will get: a few percent of imbalance remain.)
  checkLayout(l, 3, opt);
  EXPECT_LT(l.layout.box[1].hi[0] - l.layout.box[1].lo[0],
            l.layout.box[2].hi[0] - l.layout.box[2].lo[0]);
  EXPECT_LE(l.imbalance(), 1.10);
  TiledLayout copy = l;
  evaluateBoxes(cost, opt, copy);
  EXPECT_DOUBLE_EQ(copy.maxCost, l.maxCost);
}

TEST(Tiled, FloorBoundsEveryLayoutFromBelow) {
  GlobalGrid g;
  g.cells = {12, 4, 10};
  std::vector<double> cost(static_cast<std::size_t>(g.cellCount()), 1.0);
  cost[at(g, 5, 1, 3)] = 100.0;  // one hot cell: a 2x2x2 box holding it costs at least 107
  EXPECT_DOUBLE_EQ(boxCostFloor(g, cost, 2), 107.0);
  for (int p : {2, 7, 16, 60}) EXPECT_GE(tiledBoxes(g, cost, p, {}).maxCost, 107.0) << p;
  // 60 boxes of 2x2x2 fill the grid: the floor is met.
  EXPECT_DOUBLE_EQ(tiledBoxes(g, cost, 60, {}).maxCost, 107.0);
}

TEST(Tiled, CellCostFromCounts) {
  GlobalGrid g;
  g.cells = {2, 1, 1};
  const std::vector<double> parts{3, 0}, contacts{5, 1};
  const auto c = tiledCellCost(g, {1.0, 2.0, 0.5}, parts, contacts);
  EXPECT_DOUBLE_EQ(c[0], 1.0 + 6.0 + 2.5);
  EXPECT_DOUBLE_EQ(c[1], 1.0 + 0.5);
  EXPECT_EQ(tiledCellCost(g, {}, {}, {}).size(), 2u);
}
