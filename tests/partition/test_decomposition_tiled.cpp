// Decomposition on a tiled layout (general boxes): the box of every rank, the owner of every
// cell and point through the tree of cut planes (equal to the layout's owner map), the wall
// tests, refusal of boxes that do not tile, the Cartesian queries refusing loudly, and HaloPlan
// forwarding to the box plan (same values as BoxHaloPlan, bit for bit).
#include <gtest/gtest.h>

#include "coloc/core/error.hpp"
#include "coloc/partition/box_halo.hpp"
#include "coloc/partition/halo.hpp"
#include "coloc/partition/tiled.hpp"
#include "tiled_layouts.hpp"

using namespace coloc;

namespace {

GlobalGrid grid(std::array<bool, 3> periodic) {
  GlobalGrid g;
  g.cells = {13, 7, 9};
  g.length = {1.3, 0.7, 0.9};
  g.origin = {-0.5, 0.25, 1.0};
  g.periodic = periodic;
  return g;
}

BoxLayout clustered(const GlobalGrid& g, int ranks) {
  return tiledBoxes(g, test::heapedCost(g, {5, g.cells[1], 4}, 20.0), ranks, {}).layout;
}

class TiledDecomposition : public ::testing::TestWithParam<std::array<bool, 3>> {};

TEST_P(TiledDecomposition, OwnersBoxesAndWalls) {
  Comm world(MPI_COMM_WORLD);
  const GlobalGrid g = grid(GetParam());
  const BoxLayout l = clustered(g, world.size());
  const Decomposition dec = decompositionOf(world, l);
  ASSERT_TRUE(dec.isTiled());
  EXPECT_EQ(dec.rank(), world.rank());
  const auto& mine = l.box[static_cast<std::size_t>(world.rank())];
  EXPECT_EQ(dec.lo(), mine.lo);
  EXPECT_EQ(dec.hi(), mine.hi);
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(dec.atLowBoundary(d), !g.periodic[d] && mine.lo[d] == 0);
    EXPECT_EQ(dec.atHighBoundary(d), !g.periodic[d] && mine.hi[d] == g.cells[d]);
  }
  const auto owner = l.ownerMap();
  for (int k = -2; k < g.cells[2] + 2; ++k)
    for (int j = -2; j < g.cells[1] + 2; ++j)
      for (int i = -2; i < g.cells[0] + 2; ++i) {
        const Int3 c{i, j, k};
        Int3 w{};
        bool outside = false;
        for (int d = 0; d < 3; ++d) {
          const int n = g.cells[d];
          w[d] = g.periodic[d] ? ((c[d] % n) + n) % n : c[d];
          outside = outside || w[d] < 0 || w[d] >= n;
        }
        const int expect =
            outside
                ? -1
                : owner[static_cast<std::size_t>(w[0] + g.cells[0] * (w[1] + g.cells[1] * w[2]))];
        ASSERT_EQ(dec.ownerOfCell(c), expect) << i << " " << j << " " << k;
        if (outside) continue;
        // The centre of the cell belongs to the same rank.
        Real3 x{};
        for (int d = 0; d < 3; ++d) x[d] = g.origin[d] + (c[d] + 0.5) * g.spacing(d);
        ASSERT_EQ(dec.ownerOfPoint(x), expect);
      }
  for (int r = 0; r < world.size(); ++r) {
    EXPECT_EQ(dec.loOf(r), l.box[static_cast<std::size_t>(r)].lo);
    EXPECT_EQ(dec.hiOf(r), l.box[static_cast<std::size_t>(r)].hi);
  }
  // The Cartesian queries have no meaning on boxes: they refuse instead of answering wrongly.
  EXPECT_THROW((void)dec.dims(), Error);
  EXPECT_THROW((void)dec.cuts(), Error);
  EXPECT_THROW((void)dec.neighbour(0, 1), Error);
  EXPECT_THROW((void)dec.coords(), Error);
}

TEST_P(TiledDecomposition, ProcessGridAsBoxesHasTheGridsOwners) {
  Comm world(MPI_COMM_WORLD);
  const GlobalGrid g = grid(GetParam());
  const Decomposition cart = Decomposition::uniform(world, g);
  const Decomposition boxes = decompositionOf(world, boxLayoutOf(cart));
  EXPECT_FALSE(cart.isTiled());
  for (int k = 0; k < g.cells[2]; ++k)
    for (int j = 0; j < g.cells[1]; ++j)
      for (int i = 0; i < g.cells[0]; ++i)
        ASSERT_EQ(boxes.ownerOfCell({i, j, k}), cart.ownerOfCell({i, j, k}));
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(boxes.atLowBoundary(d), cart.atLowBoundary(d));
    EXPECT_EQ(boxes.atHighBoundary(d), cart.atHighBoundary(d));
  }
}

TEST_P(TiledDecomposition, HaloPlanForwardsToTheBoxPlan) {
  Comm world(MPI_COMM_WORLD);
  const GlobalGrid g = grid(GetParam());
  const BoxLayout l = clustered(g, world.size());
  const Decomposition dec = decompositionOf(world, l);
  for (int stagger = -1; stagger < 3; ++stagger) {
    FieldLayout layout;
    layout.n = dec.cells();
    layout.ghost = 2;
    if (stagger >= 0) layout.stagger[stagger] = 1;
    HaloPlan viaDec(dec, layout);
    BoxHaloPlan direct(dec.comm(), l, layout);
    EXPECT_EQ(viaDec.bytesPerGather(), direct.bytesPerGather());
    Field3<double> a(layout, 0.0), b(layout, 0.0);
    forEach(layout.allocated(), [&](int i, int j, int k) {
      const double v = 1.0 + 0.25 * i + 3.0 * j - 0.5 * k + 17.0 * world.rank();
      a(i, j, k) = v;
      b(i, j, k) = v;
    });
    viaDec.gather(a);
    direct.gather(b);
    forEach(layout.allocated(), [&](int i, int j, int k) { ASSERT_EQ(a(i, j, k), b(i, j, k)); });
    for (Fold fold : {Fold::Keep, Fold::Mirror}) {
      viaDec.scatterSum(a, fold);
      direct.scatterSum(b, fold);
      forEach(layout.allocated(), [&](int i, int j, int k) { ASSERT_EQ(a(i, j, k), b(i, j, k)); });
    }
  }
}

TEST_P(TiledDecomposition, OneLayerPlanOnTwoLayerFieldsAsOnTheProcessGrid) {
  // The coupling moves one ghost layer of the fluid's two-layer fields: the tiled plan must
  // address the fields' own storage (and leave the second layer alone), as the grid's plan does.
  Comm world(MPI_COMM_WORLD);
  const GlobalGrid g = grid(GetParam());
  const Decomposition cart = Decomposition::uniform(world, g);
  const Decomposition boxes = decompositionOf(world, boxLayoutOf(cart));
  FieldLayout one, two;
  one.n = two.n = cart.cells();
  one.ghost = 1;
  two.ghost = 2;
  HaloPlan viaGrid(cart, one), viaBoxes(boxes, one);
  Field3<double> a(two, 0.0), b(two, 0.0);
  forEach(two.allocated(), [&](int i, int j, int k) {
    const double v = 1.0 + i + 16.0 * j + 256.0 * k + 4096.0 * world.rank();
    a(i, j, k) = v;
    b(i, j, k) = v;
  });
  viaGrid.gather(a);
  viaBoxes.gather(b);
  forEach(two.allocated(), [&](int i, int j, int k) { ASSERT_EQ(a(i, j, k), b(i, j, k)); });
  viaGrid.scatterSum(a, Fold::Mirror);
  viaBoxes.scatterSum(b, Fold::Mirror);
  forEach(two.allocated(), [&](int i, int j, int k) { ASSERT_EQ(a(i, j, k), b(i, j, k)); });
}

INSTANTIATE_TEST_SUITE_P(Periodicity, TiledDecomposition,
                         ::testing::Values(std::array<bool, 3>{false, false, false},
                                           std::array<bool, 3>{true, false, false},
                                           std::array<bool, 3>{true, true, true}));

TEST(TiledDecompositionInput, BoxesThatDoNotTileAreRefused) {
  Comm world(MPI_COMM_WORLD);
  const GlobalGrid g = grid({false, false, false});
  const BoxLayout l = clustered(g, world.size());
  std::vector<Int3> lo, hi;
  for (const auto& b : l.box) {
    lo.push_back(b.lo);
    hi.push_back(b.hi);
  }
  const auto refused = [&](std::vector<Int3> a, std::vector<Int3> b) {
    try {
      (void)Decomposition::fromBoxes(world, g, a, b);
    } catch (const ConfigError& e) {
      return std::string(e.what()).find("partition.boxes") != std::string::npos;
    }
    return false;
  };
  // A box count that is not the rank count.
  auto lo1 = lo, hi1 = hi;
  lo1.push_back({0, 0, 0});
  hi1.push_back({1, 1, 1});
  EXPECT_TRUE(refused(lo1, hi1));
  // A gap: the first box loses its last x plane (or, on one rank, shrinks).
  auto hi2 = hi;
  hi2[0][0] -= 1;
  EXPECT_TRUE(refused(lo, hi2));
  if (world.size() > 1) {
    // An overlap: the second box grows over the first.
    auto lo3 = lo;
    lo3[1] = {0, 0, 0};
    EXPECT_TRUE(refused(lo3, hi));
  }
  // A box outside the grid.
  auto hi4 = hi;
  hi4[0][2] = g.cells[2] + 1;
  EXPECT_TRUE(refused(lo, hi4));
}

}  // namespace
