#include "coloc/partition/box_halo.hpp"

#include <fmt/format.h>
#include <mpi.h>

#include <algorithm>
#include <string>

#include "coloc/core/error.hpp"

namespace coloc {
namespace {

/// One stretch of a ghost region along an axis: extended indices [lo, hi) = src + shift.
struct Segment {
  int lo = 0, hi = 0, shift = 0, wall = 0;
};

/// The extended range of box b along d (ghost layers, staggering) cut where the mapping to the
/// domain changes: periodic images, or the domain and what lies beyond its walls.
std::vector<Segment> segments(const GlobalGrid& g, const IndexBox& b, int d, int ghost, int s) {
  const int n = g.cells[d];
  const int a = b.lo[d] - ghost, e = b.hi[d] + ghost + s;
  std::vector<Segment> out;
  if (g.periodic[d]) {
    const auto floorDiv = [](int x, int m) { return x >= 0 ? x / m : -((-x + m - 1) / m); };
    for (int k = floorDiv(a, n); k * n < e; ++k) {
      const int lo = std::max(a, k * n), hi = std::min(e, (k + 1) * n);
      if (lo < hi) out.push_back({lo, hi, k * n, 0});
    }
    return out;
  }
  const int top = n + s;  // faces 0..N on a staggered closed axis
  if (a < 0) out.push_back({a, std::min(e, 0), 0, -1});
  if (std::max(a, 0) < std::min(e, top)) out.push_back({std::max(a, 0), std::min(e, top), 0, 0});
  if (e > top) out.push_back({std::max(a, top), e, 0, +1});
  return out;
}

/// The values box q owns along d: its cells, or its faces (face N at a closed high wall).
std::pair<int, int> ownedAlong(const GlobalGrid& g, const IndexBox& q, int d, int s) {
  const int extra = (s && !g.periodic[d] && q.hi[d] == g.cells[d]) ? 1 : 0;
  return {q.lo[d], q.hi[d] + extra};
}

/// Storage offset of a local index in a field of this layout (Field3::index).
struct Offsets {
  explicit Offsets(const FieldLayout& l) {
    const Int3 e = l.extent();
    sy = e[0];
    sz = static_cast<std::ptrdiff_t>(e[0]) * e[1];
    base = l.ghost + l.ghost * sy + l.ghost * sz;
  }
  std::ptrdiff_t operator()(int i, int j, int k) const { return base + i + j * sy + k * sz; }
  std::ptrdiff_t sy = 0, sz = 0, base = 0;
};

int mirror(int x, int n) {
  if (x < 0) return std::min(-1 - x, n - 1);
  if (x >= n) return std::max(n - 1 - (x - n), 0);
  return x;
}

/// Ranks whose boxes come within `reach` cells of box b (periodic images included).
bool near(const GlobalGrid& g, const IndexBox& a, const IndexBox& b, int reach) {
  for (int d = 0; d < 3; ++d) {
    const int n = g.cells[d];
    bool hit = false;
    for (int k = g.periodic[d] ? -1 : 0; k <= (g.periodic[d] ? 1 : 0) && !hit; ++k)
      hit = b.lo[d] + k * n < a.hi[d] + reach && a.lo[d] - reach < b.hi[d] + k * n;
    if (!hit) return false;
  }
  return true;
}

}  // namespace

std::vector<HaloPiece> haloPieces(const BoxLayout& l, int r, int ghost, Int3 stagger) {
  const GlobalGrid& g = l.grid;
  const IndexBox& me = l.box[static_cast<std::size_t>(r)];
  std::array<std::vector<Segment>, 3> seg;
  for (int d = 0; d < 3; ++d) seg[d] = segments(g, me, d, ghost, stagger[d]);
  std::vector<HaloPiece> out;
  for (const auto& sz : seg[2])
    for (const auto& sy : seg[1])
      for (const auto& sx : seg[0]) {
        const std::array<const Segment*, 3> s{&sx, &sy, &sz};
        for (int q = 0; q < l.size(); ++q) {
          const IndexBox& qb = l.box[static_cast<std::size_t>(q)];
          HaloPiece p;
          p.owner = q;
          bool hit = true;
          for (int d = 0; d < 3 && hit; ++d) {
            const Segment& t = *s[d];
            const int lo = t.lo - t.shift, hi = t.hi - t.shift;
            p.shift[d] = t.shift;
            p.wall[d] = t.wall;
            if (t.wall < 0) {
              hit = qb.lo[d] == 0;
              p.src.lo[d] = lo, p.src.hi[d] = hi;
            } else if (t.wall > 0) {
              hit = qb.hi[d] == g.cells[d];
              p.src.lo[d] = lo, p.src.hi[d] = hi;
            } else {
              const auto [olo, ohi] = ownedAlong(g, qb, d, stagger[d]);
              p.src.lo[d] = std::max(lo, olo);
              p.src.hi[d] = std::min(hi, ohi);
              hit = p.src.lo[d] < p.src.hi[d];
            }
          }
          if (!hit) continue;
          if (q == r && p.shift == Int3{0, 0, 0} && p.wall == Int3{0, 0, 0}) continue;  // owned
          out.push_back(p);
        }
      }
  return out;
}

std::vector<int> haloNeighbours(const BoxLayout& l, int r, int ghost, Int3 stagger) {
  std::vector<int> out;
  for (const auto& p : haloPieces(l, r, ghost, stagger))
    if (!p.selfWall(r)) out.push_back(p.owner);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

long long haloRemoteCells(const BoxLayout& l, int r, int ghost, Int3 stagger) {
  long long n = 0;
  for (const auto& p : haloPieces(l, r, ghost, stagger))
    if (p.owner != r) n += p.src.volume();
  return n;
}

BoxHaloPlan::BoxHaloPlan(const Comm& comm, const BoxLayout& l, const FieldLayout& layout)
    : BoxHaloPlan(comm, l, layout, layout) {}

BoxHaloPlan::BoxHaloPlan(const Comm& comm, const BoxLayout& l, const FieldLayout& layout,
                         const FieldLayout& storage)
    : layout_(layout), storage_(storage) {
  if (storage.n != layout.n || storage.stagger != layout.stagger || storage.ghost < layout.ghost)
    throw Error("BoxHaloPlan: the storage layout must hold the plan's layout");
  const int me = comm.rank(), size = comm.size();
  if (l.size() != size) throw Error("BoxHaloPlan: one box per rank expected");
  const IndexBox& mine = l.box[static_cast<std::size_t>(me)];
  const GlobalGrid& g = l.grid;
  const int gw = layout.ghost;
  for (int d = 0; d < 3; ++d)
    if (layout.n[d] != mine.hi[d] - mine.lo[d])
      throw Error("BoxHaloPlan: the field layout is not this rank's box");
  // Thin boxes: the mirror of a wall ghost must land in the owner's box (HaloPlan's rule).
  for (int d = 0; d < 3; ++d) {
    const bool whole = mine.lo[d] == 0 && mine.hi[d] == g.cells[d];
    if (layout.n[d] < gw && !whole)
      throw ConfigError("partition.strategy",
                        fmt::format("tiled: a box is {} cells thick along {}, thinner than the {} "
                                    "ghost layers",
                                    layout.n[d], "xyz"[d], gw));
  }
  const Offsets at(storage);
  std::vector<int> sendCount(static_cast<std::size_t>(size), 0),
      recvCount(static_cast<std::size_t>(size), 0);

  // Imports: my pieces grouped by owner (ascending), each in the fixed order.
  const auto pieces = haloPieces(l, me, gw, layout.stagger);
  for (const auto& p : pieces) {
    if (p.selfWall(me)) {  // my own ghosts beyond a wall: folded in scatterSum
      forEach(p.src, [&](int i, int j, int k) {
        const Int3 x{i, j, k};
        Int3 to{};
        for (int d = 0; d < 3; ++d)
          to[d] = (p.wall[d] != 0 && layout.stagger[d] == 0) ? mirror(x[d], g.cells[d]) : x[d];
        foldFrom_.push_back(at(i - mine.lo[0], j - mine.lo[1], k - mine.lo[2]));
        foldTo_.push_back(at(to[0] - mine.lo[0], to[1] - mine.lo[1], to[2] - mine.lo[2]));
      });
      continue;
    }
    recvCount[static_cast<std::size_t>(p.owner)] += static_cast<int>(p.src.volume());
    neighbours_.push_back(p.owner);
  }
  std::sort(neighbours_.begin(), neighbours_.end());
  neighbours_.erase(std::unique(neighbours_.begin(), neighbours_.end()), neighbours_.end());
  for (int q : neighbours_)
    for (const auto& p : pieces) {
      if (p.owner != q || p.selfWall(me)) continue;
      forEach(p.src, [&](int i, int j, int k) {
        importAt_.push_back(at(i + p.shift[0] - mine.lo[0], j + p.shift[1] - mine.lo[1],
                               k + p.shift[2] - mine.lo[2]));
      });
    }

  // Exports: the pieces of every rank near me whose owner I am, by destination ascending.
  const int reach = gw + 1;
  for (int r = 0; r < size; ++r) {
    if (!near(g, mine, l.box[static_cast<std::size_t>(r)], reach)) continue;
    for (const auto& p : haloPieces(l, r, gw, layout.stagger)) {
      if (p.owner != me || p.selfWall(r)) continue;
      sendCount[static_cast<std::size_t>(r)] += static_cast<int>(p.src.volume());
      if (r != me) bytesPerGather_ += p.src.volume() * static_cast<long long>(sizeof(double));
      forEach(p.src, [&](int i, int j, int k) {
        const Int3 x{i, j, k};
        Int3 to{};
        for (int d = 0; d < 3; ++d)
          to[d] = (p.wall[d] != 0 && layout.stagger[d] == 0) ? mirror(x[d], g.cells[d]) : x[d];
        exportAt_.push_back(at(i - mine.lo[0], j - mine.lo[1], k - mine.lo[2]));
        mirrorAt_.push_back(at(to[0] - mine.lo[0], to[1] - mine.lo[1], to[2] - mine.lo[2]));
      });
    }
  }
  plan_ = CommPlan::fromCounts(comm, sendCount, recvCount);
}

void BoxHaloPlan::requireStorage(std::span<Field3<double>* const> fields) const {
  for (const auto* f : fields)
    if (!(f->layout() == storage_))
      throw Error("BoxHaloPlan: a field's layout is not the one the plan was built for");
}

void BoxHaloPlan::gather(std::span<Field3<double>* const> fields, Timers* timers, Exchange kind,
                         Traffic traffic) {
  requireStorage(fields);
  const double t0 = MPI_Wtime();
  const int w = static_cast<int>(fields.size());
  const auto uw = static_cast<std::size_t>(w);
  const std::span<double> buf = plan_.packBuffer(w);
  for (std::size_t k = 0; k < exportAt_.size(); ++k)
    for (std::size_t f = 0; f < uw; ++f)
      buf[k * uw + f] = fields[f]->data()[static_cast<std::size_t>(exportAt_[k])];
  if (recv_.size() < importAt_.size() * uw) recv_.resize(importAt_.size() * uw);
  const PlanTraffic t = plan_.forwardPacked(w, recv_);
  for (std::size_t k = 0; k < importAt_.size(); ++k)
    for (std::size_t f = 0; f < uw; ++f)
      fields[f]->data()[static_cast<std::size_t>(importAt_[k])] = recv_[k * uw + f];
  if (timers)
    timers->book(kind, t.remoteBytes, t.messages, t.messages > 0 ? MPI_Wtime() - t0 : 0.0, traffic);
}

void BoxHaloPlan::scatterSum(std::span<Field3<double>* const> fields, Fold fold, Timers* timers,
                             Exchange kind, Traffic traffic) {
  requireStorage(fields);
  const double t0 = MPI_Wtime();
  const int w = static_cast<int>(fields.size());
  const auto uw = static_cast<std::size_t>(w);
  // My ghosts, in import order, then zeroed (they have been handed to their owners).
  const std::size_t need = std::max(importAt_.size(), exportAt_.size()) * uw;
  if (recv_.size() < need) recv_.resize(need);
  std::vector<double>& send = sendBack_;
  if (send.size() < importAt_.size() * uw) send.resize(importAt_.size() * uw);
  for (std::size_t k = 0; k < importAt_.size(); ++k)
    for (std::size_t f = 0; f < uw; ++f) {
      double& v = fields[f]->data()[static_cast<std::size_t>(importAt_[k])];
      send[k * uw + f] = v;
      v = 0.0;
    }
  const PlanTraffic t = plan_.reverseInExportOrder({send.data(), importAt_.size() * uw}, w, recv_);
  const auto& target = fold == Fold::Mirror ? mirrorAt_ : exportAt_;
  for (std::size_t k = 0; k < exportAt_.size(); ++k)
    for (std::size_t f = 0; f < uw; ++f)
      fields[f]->data()[static_cast<std::size_t>(target[k])] += recv_[k * uw + f];
  if (timers)
    timers->book(kind, t.remoteBytes, t.messages, t.messages > 0 ? MPI_Wtime() - t0 : 0.0, traffic);
  if (fold != Fold::Mirror) return;
  if (timers) timers->start(Phase::CouplingDeposit);
  for (std::size_t k = 0; k < foldFrom_.size(); ++k)
    for (std::size_t f = 0; f < uw; ++f) {
      auto d = fields[f]->data();
      const double v = d[static_cast<std::size_t>(foldFrom_[k])];
      d[static_cast<std::size_t>(foldFrom_[k])] = 0.0;
      d[static_cast<std::size_t>(foldTo_[k])] += v;
    }
  if (timers) timers->stop(Phase::CouplingDeposit);
}

}  // namespace coloc
