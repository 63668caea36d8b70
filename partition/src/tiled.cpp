#include "coloc/partition/tiled.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "coloc/core/error.hpp"
#include "prefix_sum.hpp"

namespace coloc {
namespace {

using detail::PrefixSum;

// A cut along a shorter axis must beat the longer axis' best by more than rounding.
constexpr double kTie = 1e-9;

/// The recursive bisection over one cost table.
class Bisector {
 public:
  Bisector(const GlobalGrid& g, const PrefixSum& ps, const TiledOptions& opt,
           std::vector<IndexBox>& out)
      : g_(g), ps_(ps), opt_(opt), out_(out) {
    gran_ = std::max(1, opt.granularity);
    for (int d = 0; d < 3; ++d) {
      minCells_[d] = std::max(1, std::min(opt.minCells, g.cells[d]));
      minBlock_[d] = ((minCells_[d] + gran_ - 1) / gran_) * gran_;
    }
  }

  /// Most boxes a range [a, b) along d can be cut into.
  long long slots(int d, int a, int b) const {
    const int w = b - a;
    if (w <= 0) return 0;
    const int last = (b % gran_ == 0) ? minBlock_[d] : minCells_[d];
    if (w < last) return 1;
    return (w - last) / minBlock_[d] + 1;
  }
  long long capacity(const IndexBox& b) const {
    long long c = 1;
    for (int d = 0; d < 3; ++d) c *= slots(d, b.lo[d], b.hi[d]);
    return c;
  }
  double cost(const IndexBox& b) const {
    return ps_.box(b.lo[0], b.hi[0], b.lo[1], b.hi[1], b.lo[2], b.hi[2]) +
           (opt_.surfaceCost != 0
                ? opt_.surfaceCost * static_cast<double>(haloCells(g_, b, opt_.ghost))
                : 0.0);
  }

  void bisect(const IndexBox& box, int p, int first) {
    if (p == 1) {
      out_[static_cast<std::size_t>(first)] = box;
      return;
    }
    // Axes, longest first (ties: x before y before z): the first of the best cuts wins.
    std::array<int, 3> axes{0, 1, 2};
    std::stable_sort(axes.begin(), axes.end(),
                     [&](int a, int b) { return box.hi[a] - box.lo[a] > box.hi[b] - box.lo[b]; });
    // The halving split first, then uneven splits next to it (up to a quarter of p away) where
    // they balance better, and beyond that only while no split is legal.
    for (int d = 0; d < 3; ++d) planes(box, d, cand_[d]);
    int bestAxis = -1, bestAt = 0, bestPl = 0;
    double best = std::numeric_limits<double>::infinity();
    for (int off = 0; off < p && (bestAxis < 0 || off <= p / 4); ++off)
      for (int sign : {+1, -1}) {
        if (off == 0 && sign < 0) continue;
        const int pl = p / 2 + sign * off;
        if (pl < 1 || pl > p - 1) continue;
        for (int d : axes) {
          int cut = 0;
          double score = 0;
          if (bestCut(cand_[d], pl, p - pl, cut, score) && score < best * (1 - kTie)) {
            best = score;
            bestAxis = d;
            bestAt = cut;
            bestPl = pl;
          }
        }
      }
    if (bestAxis >= 0) {
      IndexBox lo = box, hi = box;
      lo.hi[bestAxis] = bestAt;
      hi.lo[bestAxis] = bestAt;
      bisect(lo, bestPl, first);
      bisect(hi, p - bestPl, first + bestPl);
      return;
    }
    throw ConfigError("partition.strategy", "tiled: no legal cut of a region of " +
                                                std::to_string(box.volume()) + " cells into " +
                                                std::to_string(p) + " boxes");
  }

 private:
  /// A plane along an axis: where, the cost of both sides, how many boxes each side holds.
  struct Plane {
    int at = 0;
    double lo = 0, hi = 0;
    long long capLo = 0, capHi = 0;
  };
  /// Every legal plane of the region along d (on the granularity, both sides thick enough).
  void planes(const IndexBox& box, int d, std::vector<Plane>& out) const {
    out.clear();
    const int a = box.lo[d], b = box.hi[d];
    long long cross = 1;
    for (int e = 0; e < 3; ++e)
      if (e != d) cross *= slots(e, box.lo[e], box.hi[e]);
    const int first = ((a + minBlock_[d]) + gran_ - 1) / gran_ * gran_;
    for (int c = first; c < b; c += gran_) {
      if (c - a < minCells_[d] || b - c < minCells_[d]) continue;
      IndexBox lo = box, hi = box;
      lo.hi[d] = c;
      hi.lo[d] = c;
      out.push_back({c, cost(lo), cost(hi), slots(d, a, c) * cross, slots(d, c, b) * cross});
    }
  }
  /// The plane where both sides hold their ranks with the smallest larger cost per rank; false
  /// when there is none.
  static bool bestCut(const std::vector<Plane>& planes, int pl, int pr, int& cut, double& best) {
    best = std::numeric_limits<double>::infinity();
    bool found = false;
    for (const Plane& q : planes) {
      if (q.capLo < pl || q.capHi < pr) continue;
      const double s = std::max(q.lo / pl, q.hi / pr);
      if (s < best) {
        best = s;
        cut = q.at;
        found = true;
      }
    }
    return found;
  }

  const GlobalGrid& g_;
  const PrefixSum& ps_;
  TiledOptions opt_;
  std::vector<IndexBox>& out_;
  int gran_ = 1;
  Int3 minCells_{}, minBlock_{};
  std::array<std::vector<Plane>, 3> cand_;  // scratch of one bisection step
};

}  // namespace

std::vector<int> BoxLayout::ownerMap() const {
  std::vector<int> owner(static_cast<std::size_t>(grid.cellCount()), -1);
  for (int r = 0; r < size(); ++r)
    forEach(box[static_cast<std::size_t>(r)], [&](int i, int j, int k) {
      auto& o = owner[static_cast<std::size_t>(i + grid.cells[0] * (j + grid.cells[1] * k))];
      if (o >= 0) throw Error("BoxLayout: a cell is owned by two boxes");
      o = r;
    });
  for (int o : owner)
    if (o < 0) throw Error("BoxLayout: a cell is owned by no box");
  return owner;
}

std::array<std::vector<int>, 3> BoxLayout::cutPlanes() const {
  std::array<std::vector<int>, 3> c;
  for (int d = 0; d < 3; ++d) {
    c[d] = {0, grid.cells[d]};
    for (const auto& b : box) {
      c[d].push_back(b.lo[d]);
      c[d].push_back(b.hi[d]);
    }
    std::sort(c[d].begin(), c[d].end());
    c[d].erase(std::unique(c[d].begin(), c[d].end()), c[d].end());
  }
  return c;
}

long long haloCells(const GlobalGrid& g, const IndexBox& b, int ghost) {
  long long outer = 1, inner = 1;
  for (int d = 0; d < 3; ++d) {
    const int n = b.hi[d] - b.lo[d];
    int e = n;
    if (g.periodic[d] || b.lo[d] > 0) e += std::min(ghost, g.periodic[d] ? ghost : b.lo[d]);
    if (g.periodic[d] || b.hi[d] < g.cells[d])
      e += std::min(ghost, g.periodic[d] ? ghost : g.cells[d] - b.hi[d]);
    outer *= e;
    inner *= n;
  }
  return outer - inner;
}

std::vector<double> tiledCellCost(const GlobalGrid& g, const TiledCostModel& m,
                                  std::span<const double> particles,
                                  std::span<const double> contacts) {
  const auto n = static_cast<std::size_t>(g.cellCount());
  if ((!particles.empty() && particles.size() != n) || (!contacts.empty() && contacts.size() != n))
    throw Error("tiledCellCost: one count per global cell expected");
  std::vector<double> c(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!particles.empty()) c[i] += m.perParticle * particles[i];
    if (!contacts.empty()) c[i] += m.perContact * contacts[i];
    c[i] += m.perCell;
  }
  return c;
}

void evaluateBoxes(const std::vector<double>& cost, const TiledOptions& opt, TiledLayout& l) {
  const GlobalGrid& g = l.layout.grid;
  const PrefixSum ps(g, cost);
  l.boxCost.assign(l.layout.box.size(), 0.0);
  double sum = 0;
  l.maxCost = 0;
  for (std::size_t r = 0; r < l.layout.box.size(); ++r) {
    const IndexBox& b = l.layout.box[r];
    double c = ps.box(b.lo[0], b.hi[0], b.lo[1], b.hi[1], b.lo[2], b.hi[2]);
    if (opt.surfaceCost != 0)
      c += opt.surfaceCost * static_cast<double>(haloCells(g, b, opt.ghost));
    l.boxCost[r] = c;
    sum += c;
    l.maxCost = std::max(l.maxCost, c);
  }
  l.avgCost = l.layout.box.empty() ? 0.0 : sum / static_cast<double>(l.layout.box.size());
}

TiledLayout tiledBoxes(const GlobalGrid& grid, const std::vector<double>& cost, int ranks,
                       const TiledOptions& opt) {
  if (ranks < 1) throw ConfigError("partition.strategy", "tiled: at least one rank");
  if (cost.size() != static_cast<std::size_t>(grid.cellCount()))
    throw Error("tiledBoxes: one cost per global cell expected");
  const PrefixSum ps(grid, cost);
  TiledLayout l;
  l.layout.grid = grid;
  l.layout.box.assign(static_cast<std::size_t>(ranks), IndexBox{});
  Bisector bis(grid, ps, opt, l.layout.box);
  const IndexBox all{{0, 0, 0}, grid.cells};
  if (bis.capacity(all) < ranks)
    throw ConfigError("partition.strategy",
                      "tiled: the grid holds at most " + std::to_string(bis.capacity(all)) +
                          " boxes of at least " + std::to_string(opt.minCells) +
                          " cells a side, not " + std::to_string(ranks));
  bis.bisect(all, ranks, 0);
  evaluateBoxes(cost, opt, l);
  return l;
}

}  // namespace coloc
