// The automatic process grid (Decomposition::chooseDims): legal whenever a legal grid exists,
// a clear error naming the keys when none does, MPI_Dims_create's grid kept where it is legal.
#include <gtest/gtest.h>

#include <string>

#include "coloc/core/error.hpp"
#include "coloc/partition/decomposition.hpp"

using namespace coloc;

namespace {

GlobalGrid box(Int3 cells) {
  GlobalGrid g;
  g.cells = cells;
  return g;
}

bool legal(const GlobalGrid& g, Int3 dims, int minCells) {
  for (int d = 0; d < 3; ++d)
    if (dims[d] < 1 || 1LL * dims[d] * minCells > g.cells[d]) return false;
  return true;
}

/// Brute force: does any factorisation of `ranks` (fixed entries kept) leave blocks of minCells?
bool anyLegal(const GlobalGrid& g, int ranks, int minCells, Int3 fixed) {
  for (int px = 1; px <= ranks; ++px)
    for (int py = 1; py <= ranks; ++py) {
      if (ranks % (px * py)) continue;
      const Int3 c{px, py, ranks / (px * py)};
      bool ok = legal(g, c, minCells);
      for (int d = 0; d < 3; ++d)
        if (fixed[d] > 0 && fixed[d] != c[d]) ok = false;
      if (ok) return true;
    }
  return false;
}

}  // namespace

TEST(ProcessGrid, ClusteredCaseAt64RanksIsLegal) {
  // bench/cases/clustered.json: 48 x 4 x 48 cells. MPI_Dims_create gives 4 x 4 x 4, i.e. 1-cell
  // blocks along y; the fluid needs 2.
  const auto g = box({48, 4, 48});
  const Int3 d = Decomposition::chooseDims(64, g, {0, 0, 0}, 2);
  EXPECT_EQ(d[0] * d[1] * d[2], 64);
  EXPECT_TRUE(legal(g, d, 2)) << d[0] << "x" << d[1] << "x" << d[2];
  EXPECT_LE(d[1], 2);
}

TEST(ProcessGrid, KeepsMpiDimsCreateWhereLegal) {
  // The grids that runs used before stay the same (answers are compared across rank counts).
  EXPECT_EQ(Decomposition::chooseDims(4, box({32, 32, 32})), (Int3{2, 2, 1}));
  EXPECT_EQ(Decomposition::chooseDims(8, box({32, 32, 32}), {0, 0, 0}, 2), (Int3{2, 2, 2}));
  EXPECT_EQ(Decomposition::chooseDims(2, box({235, 47, 47}), {0, 0, 0}, 2), (Int3{2, 1, 1}));
  EXPECT_EQ(Decomposition::chooseDims(6, box({10, 40, 20}), {0, 0, 0}, 2), (Int3{1, 3, 2}));
}

TEST(ProcessGrid, LegalWheneverOneExistsOverManyCases) {
  int checked = 0, impossible = 0;
  for (const Int3 cells : {Int3{48, 4, 48}, Int3{240, 20, 240}, Int3{72, 6, 72}, Int3{110, 22, 22},
                           Int3{4, 4, 4}, Int3{3, 7, 2}, Int3{1, 1, 64}, Int3{16, 2, 2},
                           Int3{5, 5, 5}, Int3{100, 1, 1}, Int3{8, 8, 2}})
    for (int ranks = 1; ranks <= 1100; ranks += (ranks < 70 ? 1 : 37))
      for (int minCells : {1, 2})
        for (const Int3 fixed : {Int3{0, 0, 0}, Int3{0, 1, 0}, Int3{2, 0, 0}}) {
          const auto g = box(cells);
          const bool exists = anyLegal(g, ranks, minCells, fixed);
          int prod = 1;
          for (int d = 0; d < 3; ++d) prod *= fixed[d] > 0 ? fixed[d] : 1;
          if (ranks % prod != 0) continue;  // refused for another reason (tested elsewhere)
          ++checked;
          if (exists) {
            Int3 d{};
            ASSERT_NO_THROW(d = Decomposition::chooseDims(ranks, g, fixed, minCells))
                << cells[0] << "x" << cells[1] << "x" << cells[2] << " on " << ranks;
            EXPECT_EQ(1LL * d[0] * d[1] * d[2], ranks);
            EXPECT_TRUE(legal(g, d, minCells))
                << cells[0] << "x" << cells[1] << "x" << cells[2] << " on " << ranks << ": " << d[0]
                << "x" << d[1] << "x" << d[2];
            for (int a = 0; a < 3; ++a) {
              if (fixed[a] > 0) {
                EXPECT_EQ(d[a], fixed[a]);
              }
            }
          } else {
            ++impossible;
            try {
              (void)Decomposition::chooseDims(ranks, g, fixed, minCells);
              ADD_FAILURE() << "no legal grid exists for " << ranks << " ranks, yet none refused";
            } catch (const ConfigError& e) {
              const std::string m = e.what();
              EXPECT_NE(m.find("partition.dims"), std::string::npos) << m;
              EXPECT_NE(m.find("domain.cells"), std::string::npos) << m;
            }
          }
        }
  EXPECT_GT(checked, 3000);
  EXPECT_GT(impossible, 100);  // the impossible branch is exercised too
}
