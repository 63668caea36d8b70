// dem/src/ghosts.cpp — the face exchanges of the DEM on a process grid: migration in three
// sweeps, the ghost plan (build at a rebuild, update between rebuilds), and the migrant rows both
// layouts share (tiled layouts: ghosts_tiled.cpp). Rows are those of the field table (rows.hpp);
// the transport is a CommPlan.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "impl.hpp"
#include "rows.hpp"

namespace coloc::dem {

using namespace detail;

int DemSolver::Impl::neighbours(int d, int* out) const {
  int n = 0;
  for (int s = -1; s <= 1; s += 2) {
    const int r = dec.neighbour(d, s);
    if (r != MPI_PROC_NULL && (n == 0 || out[0] != r)) out[n++] = r;
  }
  return n;
}

int DemSolver::Impl::importSegments(const CommPlan& plan, int d,
                                    std::array<GhostPlan::Segment, 2>& seg, int at) const {
  const int nLo = dec.neighbour(d, -1), nHi = dec.neighbour(d, +1);
  int n = 0;
  for (const int r : {nHi, nLo}) {
    if (r == MPI_PROC_NULL || (n == 1 && r == nHi)) continue;  // both faces to one rank: once
    seg[static_cast<std::size_t>(n++)] = {plan.importOffset(r), plan.importsFrom(r), at};
    at += plan.importsFrom(r);
  }
  return n;
}

namespace {

/// First export row of face s (0 low, 1 high) in a plan grouped by rank: the block of its
/// neighbour, the low face first when both faces go to one rank.
int faceOffset(const CommPlan& plan, const int* to, int s, int lowRows) {
  return plan.exportOffset(to[s]) + (s == 1 && to[0] == to[1] ? lowRows : 0);
}

}  // namespace

int DemSolver::Impl::crossAxis(std::size_t i, int d, std::string& err) {
  double& x = p.x[d][i];
  if (!std::isfinite(x) || !std::isfinite(p.v[d][i]) || !std::isfinite(p.omega[d][i])) {
    if (err.empty())
      err = "particle " + std::to_string(p.id[i]) + " has a non-finite " +
            (!std::isfinite(x)           ? "position"
             : !std::isfinite(p.v[d][i]) ? "velocity"
                                         : "angular velocity") +
            where() + ": the run blew up (time step too large, or a NaN in the forces)";
    return kLost;
  }
  if (bins.periodic[d]) {
    const double top = bins.origin[d] + bins.L[d];
    if (x < bins.origin[d]) {
      x += bins.L[d];
      if (x >= top) x = bins.origin[d];
      return -1;
    }
    if (x >= top) {
      x -= bins.L[d];
      if (x < bins.origin[d]) x = bins.origin[d];
      return +1;
    }
  } else if (x < bins.origin[d] || x > bins.origin[d] + bins.L[d]) {
    if (err.empty())
      err = "particle " + std::to_string(p.id[i]) + " left the box through the " +
            (x < bins.origin[d] ? "low " : "high ") + kAxis[d] + " face" + where() +
            " (x = " + fmt(p.x[0][i]) + ", " + fmt(p.x[1][i]) + ", " + fmt(p.x[2][i]) +
            "): too fast for the walls, or walls are off";
    return kLost;
  }
  const long long b = bins.gbinClamped(x, d);
  return b < bins.binLo[d] ? -1 : (b >= bins.binHi[d] ? +1 : 0);
}

std::size_t DemSolver::Impl::migrantLength(std::size_t i, std::size_t W) const {
  return W + 1 + 4 * static_cast<std::size_t>(hist.hStart[i + 1] - hist.hStart[i]);
}

void DemSolver::Impl::packMigrant(std::size_t i, std::size_t W, double* out) const {
  const int h0 = hist.hStart[i], h1 = hist.hStart[i + 1];
  detail::packRow(p, kOpMigrate, i, nullptr, out);
  out += W;
  *out++ = h1 - h0;
  for (int e = h0; e < h1; ++e) {
    *out++ = hist.hKey[static_cast<std::size_t>(e)];
    for (int k = 0; k < 3; ++k)
      *out++ = hist.hS[3 * static_cast<std::size_t>(e) + static_cast<std::size_t>(k)];
  }
}

void DemSolver::Impl::unpackMigrants(const double* b, std::size_t len, std::size_t W) {
  std::size_t q = 0;
  while (q < len) {
    const std::size_t i = p.nOwned;
    detail::resizeAll(p, i + 1);
    p.nOwned = i + 1;
    detail::unpackRow(p, kOpMigrate, b + q, i, true);
    const int nh = static_cast<int>(b[q + W]);
    q += W + 1;
    ensure(hist.hKey, hist.hKey.size() + static_cast<std::size_t>(nh));
    ensure(hist.hS, hist.hS.size() + 3 * static_cast<std::size_t>(nh));
    ensure(hist.hStart, hist.hStart.size() + 1);
    for (int e = 0; e < nh; ++e, q += 4) {
      hist.hKey.push_back(b[q]);
      hist.hS.insert(hist.hS.end(), b + q + 1, b + q + 4);
    }
    hist.hStart.push_back(static_cast<int>(hist.hKey.size()));
  }
}

void DemSolver::Impl::migrate() {
  if (ghosts.tiled) {
    migrateTiled();
    return;
  }
  std::string err;
  p.nGhost = 0;
  detail::resizeAll(p, p.nOwned);
  // a migrating particle: its row of the field table (kOpMigrate), its history count, then
  // (partner id, shear 3) per history
  const std::size_t W = rowWidth(p, kOpMigrate);
  for (int d = 0; d < 3; ++d) {
    ghosts.sbuf[0].clear();
    ghosts.sbuf[1].clear();
    const std::size_t n = p.nOwned;
    std::size_t w = 0;
    int hw = 0;
    for (std::size_t i = 0; i < n; ++i) {
      int dir = crossAxis(i, d, err);
      if (dir == kLost) dir = 0;
      const int h0 = hist.hStart[i], h1 = hist.hStart[i + 1];
      if (dir != 0 && dec.neighbour(d, dir) == MPI_PROC_NULL) dir = 0;  // cannot happen
      if (dir == 0) {
        keepRow(i, w, h0, h1, hw);
        ++w;
      } else {
        auto& b = ghosts.sbuf[dir > 0 ? 1 : 0];
        const std::size_t o = b.size();
        b.resize(o + migrantLength(i, W));
        packMigrant(i, W, b.data() + o);
      }
    }
    p.nOwned = w;
    hist.truncate(w, hw);
    int nb[2];
    const int nn = neighbours(d, nb);
    if (nn == 0) continue;
    // the two faces' rows through one plan whose items are the doubles of the rows (their
    // lengths vary with the histories); the counts go to the neighbours only
    const double t0 = comm.wtime();
    const int to[2] = {dec.neighbour(d, -1), dec.neighbour(d, +1)};
    auto& sb = ghosts.sbuf;
    ghosts.counts.assign(static_cast<std::size_t>(comm.size()), 0);
    for (int s = 0; s < 2; ++s)
      if (to[s] != MPI_PROC_NULL)  // a face without a neighbour has no rows (dir = 0 above)
        ghosts.counts[static_cast<std::size_t>(to[s])] +=
            static_cast<int>(sb[static_cast<std::size_t>(s)].size());
    ghosts.mig.rebuildFromCounts(comm, ghosts.counts, std::span<const int>(nb, nn));
    const std::span<double> out = ghosts.mig.packBuffer(1);
    for (int s = 0; s < 2; ++s)
      if (to[s] != MPI_PROC_NULL)
        std::copy(sb[static_cast<std::size_t>(s)].begin(), sb[static_cast<std::size_t>(s)].end(),
                  out.data() + faceOffset(ghosts.mig, to, s, static_cast<int>(sb[0].size())));
    ghosts.rbuf.resize(ghosts.mig.importCount());
    const PlanTraffic t = ghosts.mig.forwardPacked(1, ghosts.rbuf);
    book(timers, t, nn - (nb[0] == dec.rank() ? 1 : 0), comm.wtime() - t0, Traffic::DemMigrate);
    std::array<GhostPlan::Segment, 2> seg;
    const int ns = importSegments(ghosts.mig, d, seg, 0);
    for (int g = 0; g < ns; ++g)
      unpackMigrants(ghosts.rbuf.data() + seg[static_cast<std::size_t>(g)].from,
                     static_cast<std::size_t>(seg[static_cast<std::size_t>(g)].count), W);
  }
  comm.raiseIfAny(err);
}

PlanTraffic DemSolver::Impl::forwardGhostRows(int d, unsigned op, std::size_t W) {
  // Both faces' rows of axis d (operation op, periodic shift applied) packed in place into the
  // axis's plan buffer, then sent; what arrives lands in ghosts.rbuf.
  const auto& sw = ghosts.swaps[d];
  const int to[2] = {dec.neighbour(d, -1), dec.neighbour(d, +1)};
  auto& plan = ghosts.plan[static_cast<std::size_t>(d)];
  const std::span<double> out = plan.packBuffer(static_cast<int>(W));
  for (int s = 0; s < 2; ++s) {
    if (to[s] == MPI_PROC_NULL) continue;
    double shift[3] = {0, 0, 0};
    shift[d] = sw[static_cast<std::size_t>(s)].shift;
    const int at = faceOffset(plan, to, s, static_cast<int>(sw[0].send.size()));
    detail::packRows(p, op, sw[static_cast<std::size_t>(s)].send, shift,
                     out.data() + static_cast<std::size_t>(at) * W);
  }
  ghosts.rbuf.resize(plan.importCount() * W);
  return plan.forwardPacked(static_cast<int>(W), ghosts.rbuf);
}

void DemSolver::Impl::buildGhosts() {
  if (ghosts.tiled) {
    buildGhostsTiled();
    return;
  }
  const Int3 coords = dec.coords(), dims = dec.dims();
  const std::size_t W = rowWidth(p, kOpGhostBuild);
  for (int d = 0; d < 3; ++d) {
    const std::size_t nBefore = p.size();
    auto& sw = ghosts.swaps[d];
    const int to[2] = {dec.neighbour(d, -1), dec.neighbour(d, +1)};
    ghosts.rank.clear();
    ghosts.index.clear();
    for (int s = 0; s < 2; ++s) {
      auto& f = sw[static_cast<std::size_t>(s)];
      f.send.clear();
      f.shift = 0;
      if (to[s] == MPI_PROC_NULL) continue;
      if (bins.periodic[d]) {
        if (s == 0 && coords[d] == 0) f.shift = bins.L[d];
        if (s == 1 && coords[d] == dims[d] - 1) f.shift = -bins.L[d];
      }
      const double* x = p.x[d].data();
      const double lim = s == 0 ? bins.lo[d] + rc : bins.hi[d] - rc;
      for (std::size_t i = 0; i < nBefore; ++i)
        if (s == 0 ? x[i] < lim : x[i] >= lim) f.send.push_back(static_cast<int>(i));
      ghosts.rank.insert(ghosts.rank.end(), f.send.size(), to[s]);
      ghosts.index.insert(ghosts.index.end(), f.send.begin(), f.send.end());
    }
    int nb[2];
    const int nn = neighbours(d, nb);
    ghosts.nSeg[static_cast<std::size_t>(d)] = 0;
    if (nn == 0) continue;
    // one plan per axis from the rows' destinations (counts to the two neighbours only), kept
    // for the updates
    const double t0 = comm.wtime();
    auto& plan = ghosts.plan[static_cast<std::size_t>(d)];
    plan.rebuild(comm, ghosts.rank, ghosts.index, std::span<const int>(nb, nn));
    const PlanTraffic t = forwardGhostRows(d, kOpGhostBuild, W);
    book(timers, t, nn - (nb[0] == dec.rank() ? 1 : 0), comm.wtime() - t0, Traffic::DemGhost);
    auto& seg = ghosts.seg[static_cast<std::size_t>(d)];
    const std::size_t start = p.size(), cnt = plan.importCount();
    const int ns = importSegments(plan, d, seg, static_cast<int>(start));
    ghosts.nSeg[static_cast<std::size_t>(d)] = ns;
    detail::resizeAll(p, start + cnt);
    p.nGhost += cnt;
    for (int g = 0; g < ns; ++g) {
      const auto& sg = seg[static_cast<std::size_t>(g)];
      detail::unpackRows(p, kOpGhostBuild,
                         ghosts.rbuf.data() + static_cast<std::size_t>(sg.from) * W,
                         static_cast<std::size_t>(sg.count), static_cast<std::size_t>(sg.at), true);
    }
  }
}

void DemSolver::Impl::updateGhosts() {
  if (ghosts.tiled) {
    updateGhostsTiled();
    return;
  }
  const std::size_t W = rowWidth(p, kOpGhostUpdate);
  for (int d = 0; d < 3; ++d) {
    if (ghosts.nSeg[static_cast<std::size_t>(d)] == 0) continue;
    const double t0 = comm.wtime();
    const PlanTraffic t = forwardGhostRows(d, kOpGhostUpdate, W);
    book(timers, t, 0, comm.wtime() - t0, Traffic::DemGhost);
    for (int g = 0; g < ghosts.nSeg[static_cast<std::size_t>(d)]; ++g) {
      const auto& sg = ghosts.seg[static_cast<std::size_t>(d)][static_cast<std::size_t>(g)];
      detail::unpackRows(
          p, kOpGhostUpdate, ghosts.rbuf.data() + static_cast<std::size_t>(sg.from) * W,
          static_cast<std::size_t>(sg.count), static_cast<std::size_t>(sg.at), false);
    }
  }
}

}  // namespace coloc::dem
