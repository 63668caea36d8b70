// The shared Cartesian decomposition: blocks tile the box, uneven splits, neighbours with
// periodic wrap, owners of cells, faces and points. Run at 1, 2, 3 and 4 ranks.
#include <gtest/gtest.h>

#include <numeric>

#include "coloc/core/error.hpp"
#include "coloc/partition/decomposition.hpp"

using namespace coloc;

namespace {

GlobalGrid grid(Int3 cells, std::array<bool, 3> periodic = {false, false, false}) {
  GlobalGrid g;
  g.origin = {-0.5, 1.0, 2.0};
  g.length = {1.3, 0.7, 0.5};
  g.cells = cells;
  g.periodic = periodic;
  return g;
}

class DecompositionTest : public ::testing::TestWithParam<std::array<bool, 3>> {};

}  // namespace

TEST(Decomposition, EvenCutsDifferByAtMostOne) {
  const auto c = Decomposition::evenCuts(13, 4);
  ASSERT_EQ(c, (std::vector<int>{0, 4, 7, 10, 13}));
  for (int n : {1, 5, 13, 100})
    for (int p = 1; p <= n && p <= 9; ++p) {
      const auto cuts = Decomposition::evenCuts(n, p);
      int mn = n, mx = 0;
      for (int i = 0; i < p; ++i)
        mn = std::min(mn, cuts[i + 1] - cuts[i]), mx = std::max(mx, cuts[i + 1] - cuts[i]);
      EXPECT_LE(mx - mn, 1);
      EXPECT_GE(mn, 1);
    }
}

TEST_P(DecompositionTest, BlocksTileTheBoxExactlyOnce) {
  const auto g = grid({13, 7, 5}, GetParam());
  const auto dec = Decomposition::uniform(Comm::world(), g);
  EXPECT_EQ(dec.dims()[0] * dec.dims()[1] * dec.dims()[2], dec.size());
  // Every global cell is owned by exactly one rank, and ownerOfCell agrees with the blocks.
  std::vector<int> owners(static_cast<std::size_t>(g.cellCount()), 0);
  for (int k = dec.lo()[2]; k < dec.hi()[2]; ++k)
    for (int j = dec.lo()[1]; j < dec.hi()[1]; ++j)
      for (int i = dec.lo()[0]; i < dec.hi()[0]; ++i)
        owners[static_cast<std::size_t>(i + 13 * (j + 7 * k))] += 1;
  dec.comm().sumInPlace(std::span<int>(owners));
  for (int v : owners) ASSERT_EQ(v, 1);
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 7; ++j)
      for (int i = 0; i < 13; ++i) {
        const int r = dec.ownerOfCell({i, j, k});
        const auto lo = dec.loOf(r), hi = dec.hiOf(r);
        ASSERT_TRUE(i >= lo[0] && i < hi[0] && j >= lo[1] && j < hi[1] && k >= lo[2] && k < hi[2]);
      }
  EXPECT_EQ(dec.comm().sum(dec.ownedCellCount()), g.cellCount());
}

TEST_P(DecompositionTest, NeighboursAreMutualAndWrapOnPeriodicAxes) {
  const auto g = grid({13, 7, 5}, GetParam());
  const auto dec = Decomposition::uniform(Comm::world(), g);
  for (int d = 0; d < 3; ++d) {
    for (int side : {-1, +1}) {
      const int n = dec.neighbour(d, side);
      Int3 c = dec.coords();
      c[d] += side;
      if (c[d] < 0 || c[d] >= dec.dims()[d]) {
        if (g.periodic[d]) {
          c[d] = (c[d] + dec.dims()[d]) % dec.dims()[d];
          EXPECT_EQ(n, dec.rankOfCoords(c));
        } else {
          EXPECT_EQ(n, MPI_PROC_NULL);
          EXPECT_TRUE(side < 0 ? dec.atLowBoundary(d) : dec.atHighBoundary(d));
        }
      } else {
        EXPECT_EQ(n, dec.rankOfCoords(c));
        // The neighbour's block touches mine along d and matches me across the other axes.
        const auto lo = dec.loOf(n), hi = dec.hiOf(n);
        EXPECT_EQ(side > 0 ? lo[d] : hi[d], side > 0 ? dec.hi()[d] : dec.lo()[d]);
        for (int e = 0; e < 3; ++e)
          if (e != d) {
            EXPECT_TRUE(lo[e] == dec.lo()[e] && hi[e] == dec.hi()[e]);
          }
      }
    }
  }
}

TEST_P(DecompositionTest, OwnerOfPointsAndFaces) {
  const auto g = grid({13, 7, 5}, GetParam());
  const auto dec = Decomposition::uniform(Comm::world(), g);
  // A point in the middle of every cell is owned by the cell's owner.
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 7; ++j)
      for (int i = 0; i < 13; ++i) {
        const Real3 x{g.origin[0] + (i + 0.5) * g.spacing(0),
                      g.origin[1] + (j + 0.5) * g.spacing(1),
                      g.origin[2] + (k + 0.5) * g.spacing(2)};
        ASSERT_EQ(dec.ownerOfPoint(x), dec.ownerOfCell({i, j, k}));
      }
  // The top corner of the box belongs to the last block; outside is nobody's unless periodic.
  const Real3 top{g.origin[0] + g.length[0], g.origin[1] + g.length[1], g.origin[2] + g.length[2]};
  if (!g.periodic[0] && !g.periodic[1] && !g.periodic[2]) {
    EXPECT_EQ(dec.ownerOfPoint(top), dec.ownerOfCell({12, 6, 4}));
    EXPECT_EQ(dec.ownerOfPoint({g.origin[0] - 1e-9, 1.1, 2.1}), -1);
  }
  if (g.periodic[0]) {
    EXPECT_EQ(dec.ownerOfPoint({g.origin[0] - 1e-9, 1.01, 2.01}), dec.ownerOfCell({12, 0, 0}));
  }
  // Faces: face f belongs to cell f's owner; the last face of a closed axis to the last block.
  EXPECT_EQ(dec.ownerOfFace(0, {13, 3, 2}),
            g.periodic[0] ? dec.ownerOfCell({0, 3, 2}) : dec.ownerOfCell({12, 3, 2}));
  EXPECT_EQ(dec.ownerOfFace(1, {4, 0, 2}), dec.ownerOfCell({4, 0, 2}));
}

INSTANTIATE_TEST_SUITE_P(Periodicity, DecompositionTest,
                         ::testing::Values(std::array<bool, 3>{false, false, false},
                                           std::array<bool, 3>{true, false, false},
                                           std::array<bool, 3>{true, true, true}));

TEST(Decomposition, FixedAxesAndErrors) {
  const auto comm = Comm::world();
  const auto dec = Decomposition::uniform(comm, grid({13, 7, 5}), {0, 1, 1});
  EXPECT_EQ(dec.dims()[0], comm.size());
  if (comm.size() > 1) {
    EXPECT_THROW(Decomposition::uniform(comm, grid({1, 1, 1})), ConfigError);
    EXPECT_THROW(Decomposition::uniform(comm, grid({13, 7, 5}), {comm.size() + 1, 1, 1}),
                 ConfigError);
  }
}

TEST(Decomposition, AutomaticDimsFollowTheLongAxis) {
  const auto comm = Comm::world();
  const auto dec = Decomposition::uniform(comm, grid({40, 8, 8}));
  if (comm.size() == 2 || comm.size() == 3) {
    EXPECT_EQ(dec.dims()[0], comm.size());
  }
  if (comm.size() == 4) {
    EXPECT_EQ(dec.dims()[0], 2);
  }
}
