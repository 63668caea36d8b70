// The communication plan (partition/comm_plan.hpp) at 1-4 ranks with uneven counts: forward
// (migrate, gather to several copies), reverse, reverse sum in a fixed order, variable-length
// rows, plans from counts and from neighbours, and the traffic each operation reports.
#include <gtest/gtest.h>

#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/partition/comm_plan.hpp"

using namespace coloc;

namespace {

constexpr int kW = 3;

// Rank r has 3 + 2 r items; item i goes to rank (r + i * i) % size: uneven counts, some to self.
int itemsOf(int r) {
  return 3 + 2 * r;
}
int destOf(int r, int i, int size) {
  return (r + i * i) % size;
}
double value(int r, int i, int c) {
  return 1000.0 * r + 10.0 * i + c;
}

std::vector<double> rowsOf(int r) {
  std::vector<double> v;
  for (int i = 0; i < itemsOf(r); ++i)
    for (int c = 0; c < kW; ++c) v.push_back(value(r, i, c));
  return v;
}

/// What rank `me` must receive: rows grouped by source rank ascending, in the source's order.
std::vector<double> expectedImports(int me, int size) {
  std::vector<double> v;
  for (int s = 0; s < size; ++s)
    for (int i = 0; i < itemsOf(s); ++i)
      if (destOf(s, i, size) == me)
        for (int c = 0; c < kW; ++c) v.push_back(value(s, i, c));
  return v;
}

}  // namespace

TEST(CommPlan, ForwardGroupsBySourceInOrder) {
  const Comm comm = Comm::world();
  const int me = comm.rank(), size = comm.size();
  std::vector<int> dest;
  for (int i = 0; i < itemsOf(me); ++i) dest.push_back(destOf(me, i, size));
  CommPlan plan = CommPlan::fromDestinations(comm, dest);
  EXPECT_EQ(plan.exportCount(), static_cast<std::size_t>(itemsOf(me)));
  const auto expected = expectedImports(me, size);
  ASSERT_EQ(plan.importCount() * kW, expected.size());
  std::vector<double> got(expected.size(), -1);
  const auto src = rowsOf(me);
  for (int repeat = 0; repeat < 2; ++repeat) {  // reused
    const PlanTraffic t = plan.forward(src, kW, got);
    EXPECT_EQ(got, expected);
    long long remote = 0, local = 0, messages = 0;
    for (int r = 0; r < size; ++r) {
      const long long b = 8LL * kW * plan.exportsTo(r);
      if (r == me) {
        local += b;
      } else if (b > 0) {
        remote += b;
        ++messages;
      }
    }
    EXPECT_EQ(t.remoteBytes, remote);
    EXPECT_EQ(t.localBytes, local);
    EXPECT_EQ(t.messages, messages);
  }
  // Back again: every row returns to the item it came from.
  for (auto& x : got) x += 0.5;
  std::vector<double> back(src.size(), 0);
  plan.reverse(got, kW, back);
  for (std::size_t k = 0; k < src.size(); ++k) EXPECT_EQ(back[k], src[k] + 0.5);
}

TEST(CommPlan, GatherToCopiesAndScatterSum) {
  // Every item of rank r is copied to every rank (ranks and indices given explicitly); each copy
  // holder adds its rank to the values and the reverse sum collects all copies on the owner.
  const Comm comm = Comm::world();
  const int me = comm.rank(), size = comm.size();
  std::vector<int> ranks, index;
  for (int r = size - 1; r >= 0; --r)
    for (int i = 0; i < itemsOf(me); ++i) {
      ranks.push_back(r);
      index.push_back(i);
    }
  CommPlan plan(comm, ranks, index);
  EXPECT_EQ(plan.exportCount(), static_cast<std::size_t>(size * itemsOf(me)));
  const auto src = rowsOf(me);
  std::vector<double> copies(plan.importCount() * kW);
  plan.forward(src, kW, copies);
  std::size_t q = 0;
  for (int s = 0; s < size; ++s)
    for (int i = 0; i < itemsOf(s); ++i)
      for (int c = 0; c < kW; ++c) EXPECT_EQ(copies[q++], value(s, i, c));
  for (auto& x : copies) x = 1.0 + me;
  std::vector<double> sum(src.size(), 0.0);
  plan.reverseSum(copies, kW, sum);
  const double expected = size * (size + 1) / 2.0;
  for (double x : sum) EXPECT_EQ(x, expected);
}

TEST(CommPlan, NeighboursOnly) {
  // A ring: items go to the left and right neighbours only.
  const Comm comm = Comm::world();
  const int me = comm.rank(), size = comm.size();
  const int left = (me + size - 1) % size, right = (me + 1) % size;
  std::vector<int> ranks, index;
  for (int i = 0; i < itemsOf(me); ++i) {
    ranks.push_back(i % 2 == 0 ? left : right);
    index.push_back(i);
  }
  const std::vector<int> nb{left, right};
  CommPlan plan = CommPlan::withNeighbours(comm, ranks, index, nb);
  CommPlan ref(comm, ranks, index);
  ASSERT_EQ(plan.importCount(), ref.importCount());
  for (int r = 0; r < size; ++r) EXPECT_EQ(plan.importsFrom(r), ref.importsFrom(r));
  const auto src = rowsOf(me);
  std::vector<double> a(plan.importCount() * kW), b(a.size());
  plan.forward(src, kW, a);
  ref.forward(src, kW, b);
  EXPECT_EQ(a, b);
}

TEST(CommPlan, FromCountsNeedsNoMessages) {
  // Rank r sends r + 1 + s rows to rank s: every rank knows all counts.
  const Comm comm = Comm::world();
  const int me = comm.rank(), size = comm.size();
  std::vector<int> sc(static_cast<std::size_t>(size)), rc(sc.size());
  std::vector<double> src;
  for (int s = 0; s < size; ++s) {
    sc[static_cast<std::size_t>(s)] = me + 1 + s;
    rc[static_cast<std::size_t>(s)] = s + 1 + me;
    for (int k = 0; k < me + 1 + s; ++k) src.push_back(100.0 * me + s);
  }
  CommPlan plan = CommPlan::fromCounts(comm, sc, rc);
  std::vector<double> got(plan.importCount());
  plan.forward(src, 1, got);
  std::size_t q = 0;
  for (int s = 0; s < size; ++s)
    for (int k = 0; k < s + 1 + me; ++k) EXPECT_EQ(got[q++], 100.0 * s + me);
}

TEST(CommPlan, VariableLengthRows) {
  // Item i of rank r has i % 3 values (some empty).
  const Comm comm = Comm::world();
  const int me = comm.rank(), size = comm.size();
  std::vector<int> dest;
  std::vector<double> src;
  std::vector<long long> off{0};
  for (int i = 0; i < itemsOf(me); ++i) {
    dest.push_back(destOf(me, i, size));
    for (int c = 0; c < i % 3; ++c) src.push_back(value(me, i, c));
    off.push_back(static_cast<long long>(src.size()));
  }
  CommPlan plan = CommPlan::fromDestinations(comm, dest);
  std::vector<double> got;
  std::vector<long long> gotOff;
  plan.forwardVariable(src, off, got, gotOff);
  std::vector<double> want;
  std::vector<long long> wantOff{0};
  for (int s = 0; s < size; ++s)
    for (int i = 0; i < itemsOf(s); ++i)
      if (destOf(s, i, size) == me) {
        for (int c = 0; c < i % 3; ++c) want.push_back(value(s, i, c));
        wantOff.push_back(static_cast<long long>(want.size()));
      }
  EXPECT_EQ(got, want);
  EXPECT_EQ(gotOff, wantOff);
}

TEST(CommPlan, RejectsBadRank) {
  const Comm comm = Comm::world();
  const std::vector<int> dest{comm.size()};
  // Every rank throws before any message: nothing is left pending.
  EXPECT_THROW(CommPlan::fromDestinations(comm, dest), Error);
}

// ---- remapFields: cell and face fields between two decompositions of the same grid ----------

#include "coloc/partition/remap.hpp"

namespace {

double code(int d, int i, int j, int k) {
  return d * 1e6 + i * 1e4 + j * 100 + k;
}

}  // namespace

TEST(Remap, CellsAndFacesBetweenDecompositions) {
  const Comm comm = Comm::world();
  for (bool periodic : {false, true}) {
    GlobalGrid g;
    g.cells = {9, 5, 7};
    g.periodic = {periodic, false, periodic};
    const Decomposition a = Decomposition::uniform(comm, g);
    // Uneven cuts along the axis the uniform blocks split most.
    const Int3 dims = a.dims();
    std::array<std::vector<int>, 3> cuts;
    for (int d = 0; d < 3; ++d) {
      cuts[d] = Decomposition::evenCuts(g.cells[d], dims[d]);
      if (dims[d] > 1) cuts[d][1] = 1;  // a thin first block
    }
    const Decomposition b = Decomposition::fromCuts(comm, g, cuts);
    for (int stagger = -1; stagger < 3; ++stagger) {
      const FieldLayout la = stagger < 0 ? cellLayout(a, 1) : faceLayout(a, stagger, 1);
      const FieldLayout lb = stagger < 0 ? cellLayout(b, 1) : faceLayout(b, stagger, 1);
      Field3<double> f0(la, -1.0), f1(la, -1.0), h0(lb, -2.0), h1(lb, -2.0);
      const IndexBox own = ownedGlobalBox(a, a.rank(), stagger);
      forEach(own, [&](int i, int j, int k) {
        const Int3 lo = a.lo();
        f0(i - lo[0], j - lo[1], k - lo[2]) = code(0, i, j, k);
        f1(i - lo[0], j - lo[1], k - lo[2]) = code(1, i, j, k);
      });
      const Field3<double>* src[] = {&f0, &f1};
      Field3<double>* dst[] = {&h0, &h1};
      remapFields(a, src, b, dst, stagger);
      const IndexBox mine = ownedGlobalBox(b, b.rank(), stagger);
      forEach(mine, [&](int i, int j, int k) {
        const Int3 lo = b.lo();
        ASSERT_EQ(h0(i - lo[0], j - lo[1], k - lo[2]), code(0, i, j, k)) << stagger;
        ASSERT_EQ(h1(i - lo[0], j - lo[1], k - lo[2]), code(1, i, j, k)) << stagger;
      });
      // Ghosts untouched.
      EXPECT_EQ(h0(-1, 0, 0), -2.0);
    }
  }
}
