// Halo exchange (gather) and reverse halo sum (scatter-sum) of cell and face fields, checked
// value by value against global indices, at 1-4 ranks, sizes that do not divide, with and
// without periodic axes, ghost widths 1 and 2.
#include <gtest/gtest.h>

#include "coloc/partition/field.hpp"
#include "coloc/partition/halo.hpp"

using namespace coloc;

namespace {

struct Param {
  std::array<bool, 3> periodic;
  int ghost;
};

class HaloTest : public ::testing::TestWithParam<Param> {};

constexpr double kSentinel = -7.0;

GlobalGrid makeGrid(const Param& p) {
  GlobalGrid g;
  g.cells = {11, 6, 5};
  g.periodic = p.periodic;
  return g;
}

/// Global index along d of local index i, with periodic wrap; -1 when outside a closed box.
/// `faces`: the axis is staggered (valid face indices 0..N on a closed axis, wrap mod N if
/// periodic).
int globalAlong(const GlobalGrid& g, int d, int lo, int i, bool faces) {
  const int n = g.cells[d];
  int x = lo + i;
  if (g.periodic[d]) return ((x % n) + n) % n;
  if (x < 0 || x > n - (faces ? 0 : 1)) return -1;
  return x;
}

double code(Int3 gidx, const GlobalGrid& g) {
  return 1.0 + gidx[0] + (g.cells[0] + 1) * (gidx[1] + (g.cells[1] + 1) * gidx[2]);
}

void checkGather(const Decomposition& dec, const FieldLayout& layout, const IndexBox& owned) {
  const auto& g = dec.grid();
  Field3<double> f(layout, kSentinel);
  forEach(owned, [&](int i, int j, int k) {
    f(i, j, k) = code({dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k}, g);
  });
  HaloPlan plan(dec, layout);
  Timers timers;
  plan.gather(f, &timers);
  plan.gather(f, &timers);  // reuse of the plan and its buffers
  int bad = 0;
  forEach(layout.allocated(), [&](int i, int j, int k) {
    const Int3 loc{i, j, k};
    Int3 gi{};
    bool valid = true;
    for (int d = 0; d < 3; ++d) {
      gi[d] = globalAlong(g, d, dec.lo()[d], loc[d], layout.stagger[d] == 1);
      valid = valid && gi[d] >= 0;
    }
    const double expect = valid ? code(gi, g) : kSentinel;
    if (f(i, j, k) != expect && bad++ < 5)
      ADD_FAILURE() << "local (" << i << "," << j << "," << k << ") got " << f(i, j, k)
                    << " expected " << expect;
  });
  EXPECT_EQ(bad, 0);
  if (dec.size() > 1 || g.periodic[0] || g.periodic[1] || g.periodic[2]) {
    EXPECT_GE(dec.comm().sum(timers.messages(Exchange::IntraPhysics)), 0);
  }
}

/// Expected scatter-sum result at my owned index: how many allocated copies, over all ranks,
/// map to the same global index (wrap on periodic axes; mirror on closed axes for cells).
double expectedCopies(const Decomposition& dec, const FieldLayout& myLayout, Int3 globalIdx,
                      bool mirror) {
  const auto& g = dec.grid();
  double count = 0;
  for (int r = 0; r < dec.size(); ++r) {
    const auto lo = dec.loOf(r), hi = dec.hiOf(r);
    FieldLayout l = myLayout;
    for (int d = 0; d < 3; ++d) l.n[d] = hi[d] - lo[d];
    forEach(l.allocated(), [&](int i, int j, int k) {
      const Int3 loc{i, j, k};
      for (int d = 0; d < 3; ++d) {
        int x = lo[d] + loc[d];
        const int n = g.cells[d];
        if (g.periodic[d]) {
          x = ((x % n) + n) % n;
        } else if (l.stagger[d]) {
          if (x < 0 || x > n) return;
        } else if (x < 0 || x >= n) {
          if (!mirror) return;
          x = x < 0 ? -1 - x : 2 * n - 1 - x;
        }
        if (x != globalIdx[d]) return;
      }
      count += 1;
    });
  }
  return count;
}

void checkScatterSum(const Decomposition& dec, const FieldLayout& layout, const IndexBox& owned,
                     Fold fold) {
  Field3<double> f(layout, 1.0);
  const double before = dec.comm().sum(static_cast<double>(layout.size()));
  HaloPlan plan(dec, layout);
  plan.scatterSum(f, fold);
  double ownedSum = 0;
  int bad = 0;
  forEach(owned, [&](int i, int j, int k) {
    const Int3 gi{dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k};
    const double expect = expectedCopies(dec, layout, gi, fold == Fold::Mirror);
    ownedSum += f(i, j, k);
    if (f(i, j, k) != expect && bad++ < 5)
      ADD_FAILURE() << "owned (" << i << "," << j << "," << k << ") got " << f(i, j, k)
                    << " expected " << expect;
  });
  EXPECT_EQ(bad, 0);
  if (fold == Fold::Mirror && layout.stagger == Int3{0, 0, 0}) {
    // Every contribution lands on an owner: the total is conserved exactly.
    EXPECT_EQ(dec.comm().sum(ownedSum), before);
    double ghostSum = 0;
    forEach(layout.allocated(), [&](int i, int j, int k) {
      if (!layout.interior().contains(i, j, k)) ghostSum += std::abs(f(i, j, k));
    });
    EXPECT_EQ(ghostSum, 0.0);
  }
}

}  // namespace

TEST_P(HaloTest, CellGatherMatchesGlobalIndices) {
  const auto dec = Decomposition::uniform(Comm::world(), makeGrid(GetParam()));
  const auto layout = cellLayout(dec, GetParam().ghost);
  checkGather(dec, layout, layout.interior());
}

TEST_P(HaloTest, FaceGatherMatchesGlobalIndices) {
  const auto dec = Decomposition::uniform(Comm::world(), makeGrid(GetParam()));
  for (int d = 0; d < 3; ++d)
    checkGather(dec, faceLayout(dec, d, GetParam().ghost), faceOwned(dec, d));
}

TEST_P(HaloTest, CellScatterSumAddsEveryCopyToItsOwner) {
  const auto dec = Decomposition::uniform(Comm::world(), makeGrid(GetParam()));
  const auto layout = cellLayout(dec, GetParam().ghost);
  checkScatterSum(dec, layout, layout.interior(), Fold::Mirror);
  checkScatterSum(dec, layout, layout.interior(), Fold::Keep);
}

TEST_P(HaloTest, FaceScatterSumAddsEveryCopyToItsOwner) {
  const auto dec = Decomposition::uniform(Comm::world(), makeGrid(GetParam()));
  for (int d = 0; d < 3; ++d)
    checkScatterSum(dec, faceLayout(dec, d, GetParam().ghost), faceOwned(dec, d), Fold::Keep);
}

INSTANTIATE_TEST_SUITE_P(Layouts, HaloTest,
                         ::testing::Values(Param{{false, false, false}, 1},
                                           Param{{true, false, false}, 1},
                                           Param{{true, true, true}, 1},
                                           Param{{false, true, false}, 2},
                                           Param{{true, true, true}, 2}));

TEST(Halo, ScatterSumConservesAnArbitraryDeposit) {
  // Irregular values (not all ones): the sum over owned cells after the reverse halo sum equals
  // the sum over all allocated cells before, exactly (values are dyadic so addition is exact).
  GlobalGrid g;
  g.cells = {9, 7, 4};
  g.periodic = {true, false, false};
  const auto dec = Decomposition::uniform(Comm::world(), g);
  CellField f(cellLayout(dec, 2));
  double before = 0;
  int n = 0;
  forEach(f.allocated(), [&](int i, int j, int k) {
    f(i, j, k) = 0.125 * ((n++ * 7 + dec.rank() * 3) % 17);
    before += f(i, j, k);
  });
  HaloPlan plan(dec, f.layout());
  plan.scatterSum(f, Fold::Mirror);
  double after = 0;
  forEach(f.interior(), [&](int i, int j, int k) { after += f(i, j, k); });
  EXPECT_EQ(dec.comm().sum(after), dec.comm().sum(before));
}
