// The partition strategies as objects (PartitionStrategy): the names the key accepts, the
// layouts each chooses for 1-7 ranks on a grid that no rank count divides, and the measure the
// re-balance verdict takes of a layout (evaluate) against the one the strategy took of its own.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/partition/strategy.hpp"

using namespace coloc;

namespace {

GlobalGrid grid() {
  GlobalGrid g;
  g.length = {0.16, 0.09, 0.11};
  g.cells = {16, 9, 11};
  return g;
}

/// Particles in the lowest third along z (a bed), 6 a cell, more towards low x.
std::vector<double> bedCount(const GlobalGrid& g) {
  std::vector<double> n(static_cast<std::size_t>(g.cellCount()), 0.0);
  for (int k = 0; k < g.cells[2] / 3; ++k)
    for (int j = 0; j < g.cells[1]; ++j)
      for (int i = 0; i < g.cells[0]; ++i)
        n[static_cast<std::size_t>(i + g.cells[0] * (j + g.cells[1] * k))] =
            6.0 + (i < g.cells[0] / 2 ? 4.0 : 0.0);
  return n;
}

std::vector<double> costOf(const std::vector<double>& count) {
  std::vector<double> c(count.size());
  for (std::size_t i = 0; i < c.size(); ++i) c[i] = 1.0 + 2.0 * count[i];
  return c;
}

/// Every cell of the grid in exactly one box (BoxLayout::ownerMap throws otherwise).
void expectTiles(const BoxLayout& l, int ranks, const std::string& what) {
  ASSERT_EQ(l.size(), ranks) << what;
  std::vector<int> owner;
  ASSERT_NO_THROW(owner = l.ownerMap()) << what;
  std::vector<long long> cells(static_cast<std::size_t>(ranks), 0);
  for (int o : owner) ++cells.at(static_cast<std::size_t>(o));
  for (int r = 0; r < ranks; ++r)
    EXPECT_EQ(cells[static_cast<std::size_t>(r)], l.box[static_cast<std::size_t>(r)].volume())
        << what << " rank " << r;
}

}  // namespace

TEST(PartitionStrategy, NamesAndUnknownName) {
  EXPECT_EQ(PartitionStrategy::names(),
            (std::vector<std::string>{"uniform", "balanced", "independent", "tiled"}));
  for (const PartitionStrategy* s : PartitionStrategy::all())
    EXPECT_EQ(&PartitionStrategy::named(s->name()), s);
  try {
    PartitionStrategy::named("coloc");
    FAIL() << "an unknown name was accepted";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("partition.strategy"), std::string::npos) << m;
    EXPECT_NE(m.find("'coloc'"), std::string::npos) << m;
    for (const auto& n : PartitionStrategy::names()) EXPECT_NE(m.find(n), std::string::npos) << m;
  }
  try {
    PartitionStrategy::named("Balanced", "--strategy");
    FAIL() << "names are exact";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--strategy"), std::string::npos) << e.what();
  }
}

TEST(PartitionStrategy, LayoutsTileTheGridOnAnyRankCount) {
  const GlobalGrid g = grid();
  const auto count = bedCount(g);
  const auto cost = costOf(count);
  const CellWork work{cost, count, 0.5};
  for (const PartitionStrategy* s : PartitionStrategy::all())
    for (int ranks = 1; ranks <= 7; ++ranks) {
      const std::string what = std::string(s->name()) + " on " + std::to_string(ranks);
      StrategyInput in;
      in.grid = g;
      in.ranks = ranks;
      const StrategyLayout l = s->layout(in, work);
      EXPECT_EQ(l.isGrid(), s->gridLayout()) << what;
      EXPECT_EQ(l.particleBlocks.has_value(), s->ownParticleBlocks()) << what;
      expectTiles(l.fluid, ranks, what + " fluid");
      expectTiles(l.particles, ranks, what + " particles");
      if (l.isGrid()) {  // the boxes are the blocks'
        EXPECT_EQ(l.fluidBlocks->size(), ranks) << what;
        for (int r = 0; r < ranks; ++r) {
          EXPECT_EQ(l.fluid.box[static_cast<std::size_t>(r)].lo, l.fluidBlocks->lo(r)) << what;
          EXPECT_EQ(l.fluid.box[static_cast<std::size_t>(r)].hi, l.fluidBlocks->hi(r)) << what;
        }
      }
      EXPECT_GE(l.modelledImbalance, 1.0 - 1e-12) << what;
      // A fluid-only run keeps the start layout; so do check and plan (layoutFor).
      const StrategyLayout fluidOnly = s->layoutFor(RunMode::FluidOnly, in, work);
      const StrategyLayout start = s->startLayout(in, work.haloCell);
      ASSERT_EQ(fluidOnly.fluid.box.size(), start.fluid.box.size()) << what;
      for (std::size_t r = 0; r < start.fluid.box.size(); ++r) {
        EXPECT_EQ(fluidOnly.fluid.box[r].lo, start.fluid.box[r].lo) << what;
        EXPECT_EQ(fluidOnly.fluid.box[r].hi, start.fluid.box[r].hi) << what;
      }
      EXPECT_FALSE(fluidOnly.particleBlocks.has_value()) << what;
    }
}

TEST(PartitionStrategy, EvaluateMeasuresAsTheLayoutDid) {
  // The re-balance verdict compares the blocks in use, measured by evaluate(), with the new
  // layout's own figures: a layout measured again must give its own figures exactly.
  const GlobalGrid g = grid();
  const auto count = bedCount(g);
  const auto cost = costOf(count);
  const CellWork work{cost, count, 0.5};
  for (const PartitionStrategy* s : PartitionStrategy::all())
    for (int ranks : {1, 2, 3, 5, 6}) {
      const std::string what = std::string(s->name()) + " on " + std::to_string(ranks);
      StrategyInput in;
      in.grid = g;
      in.ranks = ranks;
      const StrategyLayout l = s->layout(in, work);
      if (!s->balancesCost()) {
        EXPECT_THROW(s->evaluate(l, in, work), Error) << what;
        continue;
      }
      StrategyLayout bare;  // what layoutOf gives of a live decomposition: boxes, blocks
      bare.fluid = bare.particles = l.fluid;
      bare.fluidBlocks = l.fluidBlocks;
      const StrategyLayout m = s->evaluate(bare, in, work);
      EXPECT_EQ(m.maxCost, l.maxCost) << what;
      EXPECT_EQ(m.meanCost, l.meanCost) << what;
      EXPECT_EQ(m.modelledImbalance, l.modelledImbalance) << what;
      if (std::isnan(l.uniformImbalance)) {
        EXPECT_TRUE(std::isnan(m.uniformImbalance)) << what;
      } else {
        EXPECT_EQ(m.uniformImbalance, l.uniformImbalance) << what;
      }
      // The start layout measured on the bed is worse than the layout placed on it.
      const StrategyLayout before = s->evaluate(s->startLayout(in, work.haloCell), in, work);
      EXPECT_LE(l.maxCost, before.maxCost * (1 + 1e-12)) << what;
      if (ranks > 1) {
        EXPECT_LT(l.modelledImbalance, before.modelledImbalance) << what;
      }
    }
}
