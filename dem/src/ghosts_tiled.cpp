// dem/src/ghosts_tiled.cpp — migration and ghosts of the DEM on a tiled layout (general boxes,
// Decomposition::isTiled): no process grid, so no staged sweeps. Migration is one exchange: a
// particle leaving its box goes straight to the owner of its (periodically wrapped) position. A
// ghost build sends every owned particle to each target (a box near this one, or a periodic
// image of one, ghosts.hpp) whose bounds widened by the interaction range hold it, the position
// shifted by the image's period: on a process grid that is the set of ghosts the staged sweeps
// deliver (faces, edges, corners). The plan of the build is reused by the updates (same rows,
// same order) until the next rebuild.
#include <algorithm>
#include <cmath>
#include <span>
#include <string>

#include "impl.hpp"
#include "rows.hpp"

namespace coloc::dem {

using namespace detail;

void DemSolver::Impl::setupTargets(const BinLayout& b) {
  const auto& grid = dec.grid();
  std::vector<Int3> lo, hi;
  dec.boxes(lo, hi);
  auto& g = ghosts;
  g.tiled = true;
  g.targets.clear();
  g.near.clear();
  // bins a ghost may lie away from the box (the range is at most one bin when bins are legal;
  // wider bins of a case without particles still give a symmetric relation)
  std::array<long long, 3> reach{};
  for (int d = 0; d < 3; ++d)
    reach[d] = std::max(1LL, static_cast<long long>(std::ceil(rc / bins.bs[d])));
  const int me = dec.rank();
  for (int r = 0; r < dec.size(); ++r) {
    std::array<long long, 3> rLo{}, rHi{};
    for (int d = 0; d < 3; ++d) {
      rLo[d] = b.blockBinLo(d, lo[static_cast<std::size_t>(r)][d]);
      rHi[d] = b.blockBinLo(d, hi[static_cast<std::size_t>(r)][d]);
    }
    bool any = false;
    for (int kz = -1; kz <= 1; ++kz)
      for (int ky = -1; ky <= 1; ++ky)
        for (int kx = -1; kx <= 1; ++kx) {
          const int k[3] = {kx, ky, kz};
          bool meets = r != me || kx != 0 || ky != 0 || kz != 0;
          for (int d = 0; d < 3 && meets; ++d) {
            if (k[d] != 0 && !bins.periodic[d]) meets = false;
            // this box moved by k periods and widened by the reach, against box r (in bins:
            // symmetric, so r finds this rank among its targets too)
            const long long a = bins.binLo[d] + k[d] * bins.NbG[d] - reach[d];
            const long long e = bins.binHi[d] + k[d] * bins.NbG[d] + reach[d];
            meets = meets && a < rHi[d] && rLo[d] < e;
          }
          if (!meets) continue;
          GhostPlan::Target t;
          t.rank = r;
          for (int d = 0; d < 3; ++d) {
            t.shift[static_cast<std::size_t>(d)] = k[d] * bins.L[d];
            t.lo[static_cast<std::size_t>(d)] = b.lo(grid, d, rLo[d]) - rc;
            t.hi[static_cast<std::size_t>(d)] = b.hi(grid, d, rHi[d]) + rc;
          }
          g.targets.push_back(t);
          any = true;
        }
    if (any) g.near.push_back(r);
  }
}

void DemSolver::Impl::migrateTiled() {
  std::string err;
  p.nGhost = 0;
  detail::resizeAll(p, p.nOwned);
  auto& g = ghosts;
  const std::size_t W = rowWidth(p, kOpMigrate);
  const std::size_t n = p.nOwned;
  const int me = dec.rank();
  const auto size = static_cast<std::size_t>(comm.size());
  // pass 1: wrap, destination (the owner rule of the bins: bins.owns here, the tree elsewhere),
  // and the doubles going to each rank
  ensure(g.dest, n);
  g.dest.resize(n);
  g.counts.assign(size, 0);
  for (std::size_t i = 0; i < n; ++i) {
    bool lost = false;
    for (int d = 0; d < 3; ++d) lost = crossAxis(i, d, err) == kLost || lost;
    const double x[3] = {p.x[0][i], p.x[1][i], p.x[2][i]};
    int to = lost || bins.owns(x) ? me : ownerRank(x);
    if (to != me && !std::binary_search(g.near.begin(), g.near.end(), to)) {
      if (err.empty())
        err = "particle " + std::to_string(p.id[i]) + " moved beyond the boxes next to rank " +
              std::to_string(me) + "'s between two neighbour rebuilds" + where() +
              " (x = " + fmt(x[0]) + ", " + fmt(x[1]) + ", " + fmt(x[2]) +
              "): the run blew up (time step too large, or a NaN in the forces)";
      to = me;
    }
    g.dest[i] = to;
    if (to != me) g.counts[static_cast<std::size_t>(to)] += static_cast<int>(migrantLength(i, W));
  }
  const double t0 = comm.wtime();
  g.mig.rebuildFromCounts(comm, g.counts, g.near);
  const std::span<double> out = g.mig.packBuffer(1);
  g.at.resize(size);
  for (std::size_t r = 0; r < size; ++r) g.at[r] = g.mig.exportOffset(static_cast<int>(r));
  // pass 2: leavers packed by destination (in row order), the others kept in place
  std::size_t w = 0;
  int hw = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto to = static_cast<std::size_t>(g.dest[i]);
    if (g.dest[i] == me) {
      keepRow(i, w, hist.hStart[i], hist.hStart[i + 1], hw);
      ++w;
    } else {
      packMigrant(i, W, out.data() + g.at[to]);
      g.at[to] += static_cast<long long>(migrantLength(i, W));
    }
  }
  p.nOwned = w;
  hist.truncate(w, hw);
  g.rbuf.resize(g.mig.importCount());
  const PlanTraffic t = g.mig.forwardPacked(1, g.rbuf);
  const bool self = std::binary_search(g.near.begin(), g.near.end(), me);
  book(timers, t, static_cast<long long>(g.near.size()) - (self ? 1 : 0), comm.wtime() - t0,
       Traffic::DemMigrate);
  // arrivals by source rank, ascending, each in its source's row order
  unpackMigrants(g.rbuf.data(), g.rbuf.size(), W);
  comm.raiseIfAny(err);
}

PlanTraffic DemSolver::Impl::forwardTargetRows(unsigned op, std::size_t W) {
  // The build listed its rows target by target, targets by rank: the plan's export order (grouped
  // by rank, stable) is that order, so each target's rows are one run with one shift.
  auto& g = ghosts;
  const std::span<double> out = g.box.packBuffer(static_cast<int>(W));
  const auto idx = g.box.exportIndex();
  std::size_t k = 0;
  for (std::size_t t = 0; t < g.targets.size(); ++t) {
    const auto c = static_cast<std::size_t>(g.runs[t]);
    detail::packRows(p, op, idx.subspan(k, c), g.targets[t].shift.data(), out.data() + k * W);
    k += c;
  }
  g.rbuf.resize(g.box.importCount() * W);
  return g.box.forwardPacked(static_cast<int>(W), g.rbuf);
}

void DemSolver::Impl::buildGhostsTiled() {
  auto& g = ghosts;
  const std::size_t n = p.nOwned;
  // only a particle within the range of a face of this box can lie near another box (or image)
  g.cand.clear();
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      if (p.x[d][i] < bins.lo[d] + rc || p.x[d][i] >= bins.hi[d] - rc) {
        ensure(g.cand, g.cand.size() + 1);
        g.cand.push_back(static_cast<int>(i));
        break;
      }
  g.rank.clear();
  g.index.clear();
  g.runs.assign(g.targets.size(), 0);
  for (std::size_t t = 0; t < g.targets.size(); ++t) {
    const auto& tg = g.targets[t];
    for (const int c : g.cand) {
      const auto i = static_cast<std::size_t>(c);
      bool in = true;
      for (int d = 0; d < 3 && in; ++d) {
        const double y = p.x[d][i] + tg.shift[static_cast<std::size_t>(d)];
        in = y >= tg.lo[static_cast<std::size_t>(d)] && y < tg.hi[static_cast<std::size_t>(d)];
      }
      if (!in) continue;
      ensure(g.rank, g.rank.size() + 1);
      ensure(g.index, g.index.size() + 1);
      g.rank.push_back(tg.rank);
      g.index.push_back(c);
      ++g.runs[t];
    }
  }
  const std::size_t W = rowWidth(p, kOpGhostBuild);
  const double t0 = comm.wtime();
  g.box.rebuild(comm, g.rank, g.index, g.near);
  const PlanTraffic t = forwardTargetRows(kOpGhostBuild, W);
  const bool self = std::binary_search(g.near.begin(), g.near.end(), dec.rank());
  book(timers, t, static_cast<long long>(g.near.size()) - (self ? 1 : 0), comm.wtime() - t0,
       Traffic::DemGhost);
  // the ghosts by source rank, target image, source row (the plan's import order)
  const std::size_t start = p.size(), cnt = g.box.importCount();
  detail::resizeAll(p, start + cnt);
  p.nGhost += cnt;
  detail::unpackRows(p, kOpGhostBuild, g.rbuf.data(), cnt, start, true);
}

void DemSolver::Impl::updateGhostsTiled() {
  const std::size_t W = rowWidth(p, kOpGhostUpdate);
  const double t0 = comm.wtime();
  const PlanTraffic t = forwardTargetRows(kOpGhostUpdate, W);
  book(timers, t, 0, comm.wtime() - t0, Traffic::DemGhost);
  detail::unpackRows(p, kOpGhostUpdate, ghosts.rbuf.data(), ghosts.box.importCount(), p.nOwned,
                     false);
}

}  // namespace coloc::dem
