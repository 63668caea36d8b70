// Halos on tiled layouts (general boxes): gathered ghosts equal the global field, the reverse
// sum equals the serial sum, at any rank count, sizes that do not divide, periodic and closed
// axes, ghost widths 1 and 2; on a Cartesian layout the box plan gives HaloPlan's results.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "coloc/partition/box_halo.hpp"
#include "coloc/partition/halo.hpp"
#include "coloc/partition/tiled.hpp"
#include "tiled_layouts.hpp"

using namespace coloc;

namespace {

struct Param {
  std::array<bool, 3> periodic;
  int ghost;
};

class BoxHaloTest : public ::testing::TestWithParam<Param> {};

constexpr double kSentinel = -7.0;

GlobalGrid makeGrid(const Param& p) {
  GlobalGrid g;
  g.cells = {13, 7, 9};
  g.periodic = p.periodic;
  return g;
}

/// A tiled layout of the communicator's ranks on a cost clustered in a corner.
BoxLayout tiledLayout(const GlobalGrid& g, int ranks, int ghost) {
  TiledOptions opt;
  opt.minCells = ghost;
  return tiledBoxes(g, test::heapedCost(g, {5, g.cells[1], 4}, 20.0), ranks, opt).layout;
}

/// An extended global index along one axis: its image in the domain, whether it lies beyond a
/// closed wall, and the cell whose owner holds it.
struct Along {
  int wrapped = 0;
  bool beyond = false;
  int ownerCell = 0;
};
Along along(const GlobalGrid& g, int d, int x, int s) {
  const int n = g.cells[d];
  Along a;
  a.wrapped = g.periodic[d] ? ((x % n) + n) % n : x;
  a.beyond = !g.periodic[d] && (x < 0 || x >= n + s);
  a.ownerCell = std::clamp(a.wrapped, 0, n - 1);
  return a;
}

double code(Int3 x) {
  return 1.0 + (x[0] + 8) + 40.0 * ((x[1] + 8) + 40.0 * (x[2] + 8));
}

bool inBox(const IndexBox& b, Int3 c) {
  return b.contains(c[0], c[1], c[2]);
}

void checkGather(const Comm& world, const BoxLayout& l, const FieldLayout& layout) {
  const auto& g = l.grid;
  const IndexBox& mine = l.box[static_cast<std::size_t>(world.rank())];
  Field3<double> f(layout, kSentinel);
  // Owned values and my own ghosts beyond the walls carry the code of their global index.
  forEach(layout.allocated(), [&](int i, int j, int k) {
    const Int3 loc{i, j, k};
    Int3 w{}, cell{};
    bool beyond = false, owned = true;
    for (int d = 0; d < 3; ++d) {
      const Along a = along(g, d, mine.lo[d] + loc[d], layout.stagger[d]);
      w[d] = a.wrapped;
      cell[d] = a.ownerCell;
      beyond = beyond || a.beyond;
      const int top = layout.stagger[d] && !g.periodic[d] && mine.hi[d] == g.cells[d] ? 1 : 0;
      owned = owned && loc[d] >= 0 && loc[d] < layout.n[d] + top;
    }
    if (owned ||
        (beyond && inBox(mine, cell) && w == Int3{mine.lo[0] + i, mine.lo[1] + j, mine.lo[2] + k}))
      f(i, j, k) = code(w);
  });
  BoxHaloPlan plan(world, l, layout);
  Timers timers;
  plan.gather(f, &timers);
  plan.gather(f, &timers);  // the plan and its buffers reused
  int bad = 0;
  forEach(layout.allocated(), [&](int i, int j, int k) {
    const Int3 loc{i, j, k};
    Int3 w{};
    for (int d = 0; d < 3; ++d) w[d] = along(g, d, mine.lo[d] + loc[d], layout.stagger[d]).wrapped;
    if (f(i, j, k) != code(w) && bad++ < 5)
      ADD_FAILURE() << "rank " << world.rank() << " local (" << i << "," << j << "," << k
                    << ") stagger " << layout.stagger[0] << layout.stagger[1] << layout.stagger[2]
                    << ": " << f(i, j, k) << " != " << code(w);
  });
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(timers.bytes(Exchange::IntraPhysics), 2 * plan.bytesPerGather());
}

/// Small integer contributions: every sum is exact.
double contribution(int rank, Int3 x) {
  return 1.0 + rank + 3.0 * (((x[0] + 8) * 7 + (x[1] + 8) * 3 + (x[2] + 8)) % 11);
}

void checkScatter(const Comm& world, const BoxLayout& l, int ghost, Fold fold) {
  const auto& g = l.grid;
  const int me = world.rank();
  // The serial reference: every rank's contributions, each moved where the sum puts it.
  std::map<std::array<int, 3>, double> ref;
  for (int r = 0; r < l.size(); ++r) {
    const IndexBox& b = l.box[static_cast<std::size_t>(r)];
    const FieldLayout lay{{b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]}, ghost};
    forEach(lay.allocated(), [&](int i, int j, int k) {
      Int3 x{b.lo[0] + i, b.lo[1] + j, b.lo[2] + k}, t{};
      for (int d = 0; d < 3; ++d) {
        t[d] = along(g, d, x[d], 0).wrapped;
        if (fold == Fold::Mirror && t[d] < 0) t[d] = std::min(-1 - t[d], g.cells[d] - 1);
        if (fold == Fold::Mirror && t[d] >= g.cells[d])
          t[d] = std::max(2 * g.cells[d] - 1 - t[d], 0);
      }
      ref[t] += contribution(r, x);
    });
  }
  const IndexBox& mine = l.box[static_cast<std::size_t>(me)];
  const FieldLayout layout{
      {mine.hi[0] - mine.lo[0], mine.hi[1] - mine.lo[1], mine.hi[2] - mine.lo[2]}, ghost};
  Field3<double> f(layout);
  forEach(layout.allocated(), [&](int i, int j, int k) {
    f(i, j, k) = contribution(me, {mine.lo[0] + i, mine.lo[1] + j, mine.lo[2] + k});
  });
  BoxHaloPlan plan(world, l, layout);
  plan.scatterSum(f, fold);
  int bad = 0;
  forEach(layout.allocated(), [&](int i, int j, int k) {
    const Int3 loc{i, j, k};
    Int3 w{}, cell{};
    bool beyond = false;
    for (int d = 0; d < 3; ++d) {
      const Along a = along(g, d, mine.lo[d] + loc[d], 0);
      w[d] = a.wrapped;
      cell[d] = a.ownerCell;
      beyond = beyond || a.beyond;
    }
    double want = 0.0;  // ghosts are handed over and zeroed
    if (layout.interior().contains(i, j, k))
      want = ref[w];
    else if (beyond && fold == Fold::Keep && inBox(mine, cell) &&
             w == Int3{mine.lo[0] + i, mine.lo[1] + j, mine.lo[2] + k})
      want = ref[w];  // my own ghosts beyond a wall keep what lands there
    if (f(i, j, k) != want && bad++ < 5)
      ADD_FAILURE() << "rank " << me << " local (" << i << "," << j << "," << k
                    << "): " << f(i, j, k) << " != " << want;
  });
  EXPECT_EQ(bad, 0);
}

}  // namespace

TEST_P(BoxHaloTest, GatherFillsEveryGhostOfCellAndFaceFields) {
  const Comm world(MPI_COMM_WORLD);
  const auto p = GetParam();
  const auto g = makeGrid(p);
  const auto l = tiledLayout(g, world.size(), p.ghost);
  const IndexBox& b = l.box[static_cast<std::size_t>(world.rank())];
  const Int3 n{b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]};
  checkGather(world, l, {n, p.ghost, {0, 0, 0}});
  for (int d = 0; d < 3; ++d) {
    FieldLayout face{n, p.ghost, {0, 0, 0}};
    face.stagger[d] = 1;
    checkGather(world, l, face);
  }
}

TEST_P(BoxHaloTest, ScatterSumEqualsTheSerialSum) {
  const Comm world(MPI_COMM_WORLD);
  const auto p = GetParam();
  const auto l = tiledLayout(makeGrid(p), world.size(), p.ghost);
  checkScatter(world, l, p.ghost, Fold::Mirror);
  checkScatter(world, l, p.ghost, Fold::Keep);
}

TEST_P(BoxHaloTest, CartesianLayoutGivesHaloPlansValues) {
  const Comm world(MPI_COMM_WORLD);
  const auto p = GetParam();
  auto g = makeGrid(p);
  g.cells[0] = 15;  // a process grid of 7 ranks with blocks of 2 cells (13 has none)
  const auto dec = Decomposition::uniform(world, g, {0, 0, 0}, p.ghost);
  BoxLayout l;
  l.grid = g;
  for (int r = 0; r < world.size(); ++r) l.box.push_back({dec.loOf(r), dec.hiOf(r)});
  const FieldLayout layout = cellLayout(dec, p.ghost);
  for (Fold fold : {Fold::Mirror, Fold::Keep}) {
    Field3<double> a(layout), b(layout);
    forEach(layout.allocated(), [&](int i, int j, int k) {
      a(i, j, k) = b(i, j, k) =
          contribution(world.rank(), {dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k});
    });
    HaloPlan cart(dec, layout);
    BoxHaloPlan box(world, l, layout);
    cart.scatterSum(a, fold);
    box.scatterSum(b, fold);
    cart.gather(a);
    box.gather(b);
    int bad = 0;
    forEach(layout.allocated(), [&](int i, int j, int k) {
      if (a(i, j, k) != b(i, j, k) && bad++ < 5)
        ADD_FAILURE() << "rank " << world.rank() << " (" << i << "," << j << "," << k
                      << "): HaloPlan " << a(i, j, k) << " box plan " << b(i, j, k);
    });
    EXPECT_EQ(bad, 0);
  }
}

TEST(BoxHalo, NeighboursAreEveryBoxTouchingTheGhostRegion) {
  // Four boxes of a 2 x 2 x 1 arrangement, one of them split: corners count as neighbours.
  GlobalGrid g;
  g.cells = {8, 8, 2};
  BoxLayout l;
  l.grid = g;
  l.box = {{{0, 0, 0}, {4, 4, 2}},
           {{4, 0, 0}, {8, 4, 2}},
           {{0, 4, 0}, {4, 8, 2}},
           {{4, 4, 0}, {8, 6, 2}},
           {{4, 6, 0}, {8, 8, 2}}};
  EXPECT_EQ(haloNeighbours(l, 0, 1), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(haloNeighbours(l, 4, 1), (std::vector<int>{2, 3}));
  EXPECT_EQ(haloNeighbours(l, 4, 3), (std::vector<int>{0, 1, 2, 3}));  // 0 across a corner
  g.periodic = {true, true, false};
  l.grid = g;
  EXPECT_EQ(haloNeighbours(l, 4, 1), (std::vector<int>{0, 1, 2, 3}));
  BoxLayout one;
  one.grid = g;
  one.box = {{{0, 0, 0}, g.cells}};
  EXPECT_EQ(haloNeighbours(one, 0, 1), (std::vector<int>{0}));  // its own periodic image
  // Remote cells of one gather: the ghost shell less what lies beyond walls.
  EXPECT_EQ(haloRemoteCells(one, 0, 1), 0);
}

INSTANTIATE_TEST_SUITE_P(Layouts, BoxHaloTest,
                         ::testing::Values(Param{{false, false, false}, 1},
                                           Param{{false, false, false}, 2},
                                           Param{{true, false, true}, 1},
                                           Param{{true, true, true}, 2},
                                           Param{{false, true, false}, 2}));
