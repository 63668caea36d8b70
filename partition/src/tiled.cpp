#include "coloc/partition/tiled.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "coloc/core/error.hpp"
#include "prefix_sum.hpp"

namespace coloc {

BoxLayout boxLayoutOf(const Decomposition& dec) {
  BoxLayout l{dec.grid(), {}};
  std::vector<Int3> lo, hi;
  dec.boxes(lo, hi);
  for (std::size_t r = 0; r < lo.size(); ++r) l.box.push_back({lo[r], hi[r]});
  return l;
}

Decomposition decompositionOf(const Comm& comm, const BoxLayout& l) {
  std::vector<Int3> lo, hi;
  for (const auto& b : l.box) {
    lo.push_back(b.lo);
    hi.push_back(b.hi);
  }
  return Decomposition::fromBoxes(comm, l.grid, std::move(lo), std::move(hi));
}
namespace {

using detail::PrefixSum;

// A cut along a shorter axis must beat the longer axis' best by more than rounding.
constexpr double kTie = 1e-9;
// Splits of a region carried out to the end before one is chosen (see Bisector::bisect).
constexpr std::size_t kRollouts = 4;

/// The recursive bisection over one cost table.
class Bisector {
 public:
  /// `reach`: how far from halving the rank split may go, as a fraction of the ranks.
  Bisector(const GlobalGrid& g, const PrefixSum& ps, const TiledOptions& opt, double reach,
           std::vector<IndexBox>& out)
      : g_(g), ps_(ps), opt_(opt), reach_(reach), out_(out) {
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

  /// Splits the region among ranks [first, first + p). With `rollout`, the few best splits by
  /// score are each carried out greedily to the end and the one whose largest box is cheapest
  /// is taken (never worse than the greedy choice, which is among them); then the same below.
  void bisect(const IndexBox& box, int p, int first, bool rollout) {
    if (p == 1) {
      out_[static_cast<std::size_t>(first)] = box;
      return;
    }
    std::vector<Split> top;
    splits(box, p, rollout && p > 2 ? kRollouts : 1, top);
    if (top.empty())
      throw ConfigError("partition.strategy",
                        fmt::format("tiled: no legal cut of a region of {} cells into {} boxes",
                                    box.volume(), p));
    std::size_t pick = 0;
    if (top.size() > 1) {
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t c = 0; c < top.size(); ++c) {
        carryOut(box, p, first, top[c], false);
        double worst = 0;
        for (int r = first; r < first + p; ++r)
          worst = std::max(worst, cost(out_[static_cast<std::size_t>(r)]));
        if (worst < best * (1 - kTie)) best = worst, pick = c;
      }
    }
    carryOut(box, p, first, top[pick], rollout);
  }

 private:
  struct Split {
    int axis = 0, at = 0, pl = 0;
    double score = 0;
  };
  void carryOut(const IndexBox& box, int p, int first, const Split& s, bool rollout) {
    IndexBox lo = box, hi = box;
    lo.hi[s.axis] = s.at;
    hi.lo[s.axis] = s.at;
    bisect(lo, s.pl, first, rollout);
    bisect(hi, p - s.pl, first + s.pl, rollout);
  }
  /// The `k` best splits of the region by score (ascending; ties: the first tried): every
  /// legal plane, each with the rank split that suits it best: the halving split, or the split
  /// nearest to the plane's share of the cost (a bed that holds most of the work gets most of
  /// the ranks) within `reach` of halving, within what both sides can hold.
  void splits(const IndexBox& box, int p, std::size_t k, std::vector<Split>& top) {
    std::array<int, 3> axes{0, 1, 2};  // longest first (ties: x before y before z)
    std::stable_sort(axes.begin(), axes.end(),
                     [&](int a, int b) { return box.hi[a] - box.lo[a] > box.hi[b] - box.lo[b]; });
    const long long reach = static_cast<long long>(reach_ * p);
    for (int d = 0; d < 3; ++d) planes(box, d, cand_[d]);
    top.clear();
    for (int d : axes)
      for (const Plane& q : cand_[d]) {
        const long long lo = std::max<long long>(1, p - q.capHi),
                        hi = std::min<long long>(p - 1, q.capLo);
        if (lo > hi) continue;
        const long long half = p / 2;
        // the rule's window where it meets the legal splits, else the legal split nearest half
        long long wlo = std::max(lo, half - reach), whi = std::min(hi, half + reach);
        if (wlo > whi) wlo = whi = std::clamp(half, lo, hi);
        const double share = q.lo + q.hi > 0 ? p * q.lo / (q.lo + q.hi) : 0.5 * p;
        const long long f = static_cast<long long>(std::floor(share));
        for (long long pl : {half, f, f + 1}) {
          pl = std::clamp(pl, wlo, whi);
          const Split s{
              d, q.at, static_cast<int>(pl),
              std::max(q.lo / static_cast<double>(pl), q.hi / static_cast<double>(p - pl))};
          bool seen = false;
          for (const Split& t : top) seen = seen || (t.axis == d && t.at == s.at && t.pl == s.pl);
          if (seen) continue;
          auto at = top.begin();
          while (at != top.end() && !(s.score < at->score * (1 - kTie))) ++at;
          if (static_cast<std::size_t>(at - top.begin()) >= k) continue;
          top.insert(at, s);
          if (top.size() > k) top.pop_back();
        }
      }
  }
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
  const GlobalGrid& g_;
  const PrefixSum& ps_;
  TiledOptions opt_;
  double reach_ = 1.0;
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

double boxCostFloor(const GlobalGrid& grid, const std::vector<double>& cost, int minCells) {
  const PrefixSum ps(grid, cost);
  Int3 m{};
  for (int d = 0; d < 3; ++d) m[d] = std::max(1, std::min(minCells, grid.cells[d]));
  // cheapest m-box starting at each corner, then for each cell the cheapest over the corners
  // that hold it
  const Int3 nc{grid.cells[0] - m[0] + 1, grid.cells[1] - m[1] + 1, grid.cells[2] - m[2] + 1};
  std::vector<double> corner(static_cast<std::size_t>(nc[0]) * nc[1] * nc[2]);
  for (int k = 0; k < nc[2]; ++k)
    for (int j = 0; j < nc[1]; ++j)
      for (int i = 0; i < nc[0]; ++i)
        corner[static_cast<std::size_t>(i + nc[0] * (j + nc[1] * k))] =
            ps.box(i, i + m[0], j, j + m[1], k, k + m[2]);
  double floor = 0;
  forEach(IndexBox{{0, 0, 0}, grid.cells}, [&](int i, int j, int k) {
    double cheapest = std::numeric_limits<double>::infinity();
    for (int c = std::max(0, k - m[2] + 1); c <= std::min(k, nc[2] - 1); ++c)
      for (int b = std::max(0, j - m[1] + 1); b <= std::min(j, nc[1] - 1); ++b)
        for (int a = std::max(0, i - m[0] + 1); a <= std::min(i, nc[0] - 1); ++a)
          cheapest =
              std::min(cheapest, corner[static_cast<std::size_t>(a + nc[0] * (b + nc[1] * c))]);
    floor = std::max(floor, cheapest);
  });
  return floor;
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
  // Three rules for the rank split (halving only; up to a quarter of the ranks from halving;
  // any), each a full bisection. The layout with the cheapest largest box wins; layouts within
  // 0.1 % of it count as equal, and of those the one with the fewest halo cells wins (less to
  // send for the same balance; ties: the first).
  std::vector<IndexBox> boxes(static_cast<std::size_t>(ranks));
  struct Tried {
    double worst = 0;
    long long halo = 0;
    std::vector<IndexBox> boxes;
  };
  std::vector<Tried> tried;
  for (const double reach : {0.0, 0.25, 1.0}) {
    Bisector bis(grid, ps, opt, reach, boxes);
    const IndexBox all{{0, 0, 0}, grid.cells};
    if (bis.capacity(all) < ranks)
      throw ConfigError("partition.strategy",
                        fmt::format("tiled: the grid holds at most {} boxes of at least {} cells "
                                    "a side, not {}",
                                    bis.capacity(all), opt.minCells, ranks));
    bis.bisect(all, ranks, 0, /*rollout=*/true);
    Tried t{0, 0, boxes};
    for (const auto& b : boxes) {
      t.worst = std::max(t.worst, bis.cost(b));
      t.halo += haloCells(grid, b, opt.ghost);
    }
    tried.push_back(std::move(t));
  }
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : tried) best = std::min(best, t.worst);
  const Tried* pick = nullptr;
  for (const auto& t : tried)
    if (t.worst <= best * (1 + 1e-3) && (!pick || t.halo < pick->halo)) pick = &t;
  l.layout.box = pick->boxes;
  evaluateBoxes(cost, opt, l);
  return l;
}

}  // namespace coloc
