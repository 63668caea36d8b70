// dem/src/ghosts.cpp — the face exchanges of the DEM: migration in three sweeps, the ghost plan
// (build at a rebuild, update between rebuilds). Rows are those of the field table (rows.hpp); the
// transport is exchange().
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

void DemSolver::Impl::exchange(int d, int tagBase, bool sizesKnown) {
  const int nLo = dec.neighbor(d, -1), nHi = dec.neighbor(d, +1);
  const double t0 = comm.wtime();
  if (!sizesKnown) {
    ghosts.rbuf[0].resize(static_cast<std::size_t>(
        comm.exchangeCount(static_cast<int>(ghosts.sbuf[0].size()), nLo, nHi, tagBase)));
    ghosts.rbuf[1].resize(static_cast<std::size_t>(
        comm.exchangeCount(static_cast<int>(ghosts.sbuf[1].size()), nHi, nLo, tagBase + 1)));
  }
  MPI_Request req[4];
  req[0] = comm.irecv(std::span<double>(ghosts.rbuf[0]), nHi, tagBase + 2);
  req[1] = comm.irecv(std::span<double>(ghosts.rbuf[1]), nLo, tagBase + 3);
  req[2] = comm.isend(std::span<const double>(ghosts.sbuf[0]), nLo, tagBase + 2);
  req[3] = comm.isend(std::span<const double>(ghosts.sbuf[1]), nHi, tagBase + 3);
  Comm::waitAll(std::span<MPI_Request>(req, 4));
  long long bytes = 0, msgs = 0;
  const int me = dec.rank();
  for (int s = 0; s < 2; ++s) {
    const int to = s == 0 ? nLo : nHi;
    if (to == MPI_PROC_NULL || to == me) continue;
    bytes +=
        static_cast<long long>(ghosts.sbuf[static_cast<std::size_t>(s)].size() * sizeof(double));
    msgs += sizesKnown ? 1 : 2;
  }
  if (msgs > 0)
    timers.book(Exchange::IntraPhysics, bytes, msgs, comm.wtime() - t0,
                tagBase >= kTagMigCount && tagBase < kTagMigCount + 30 ? Traffic::DemMigrate
                                                                       : Traffic::DemGhost);
}

void DemSolver::Impl::migrate() {
  std::string err;
  p.nGhost = 0;
  detail::resizeAll(p, p.nOwned);
  // a migrating particle: its row of the field table (kOpMigrate), its history count, then
  // (partner id, shear 3) per history
  const std::size_t W = detail::rowWidth(p, kOpMigrate);
  for (int d = 0; d < 3; ++d) {
    ghosts.sbuf[0].clear();
    ghosts.sbuf[1].clear();
    const std::size_t n = p.nOwned;
    std::size_t w = 0;
    int hw = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double& x = p.x[d][i];
      int dir = 0;
      if (!std::isfinite(x) || !std::isfinite(p.v[d][i]) || !std::isfinite(p.omega[d][i])) {
        if (err.empty())
          err = "particle " + std::to_string(p.id[i]) + " has a non-finite " +
                (!std::isfinite(x)           ? "position"
                 : !std::isfinite(p.v[d][i]) ? "velocity"
                                             : "angular velocity") +
                where() + ": the run blew up (time step too large, or a NaN in the forces)";
        dir = 0;
      } else if (bins.periodic[d]) {
        const double top = bins.origin[d] + bins.L[d];
        if (x < bins.origin[d]) {
          x += bins.L[d];
          if (x >= top) x = bins.origin[d];
          dir = -1;
        } else if (x >= top) {
          x -= bins.L[d];
          if (x < bins.origin[d]) x = bins.origin[d];
          dir = +1;
        } else {
          const long long b = bins.gbinClamped(x, d);
          dir = b < bins.binLo[d] ? -1 : (b >= bins.binHi[d] ? +1 : 0);
        }
      } else if (x < bins.origin[d] || x > bins.origin[d] + bins.L[d]) {
        if (err.empty())
          err = "particle " + std::to_string(p.id[i]) + " left the box through the " +
                (x < bins.origin[d] ? "low " : "high ") + kAxis[d] + " face" + where() +
                " (x = " + fmt(p.x[0][i]) + ", " + fmt(p.x[1][i]) + ", " + fmt(p.x[2][i]) +
                "): too fast for the walls, or walls are off";
      } else {
        const long long b = bins.gbinClamped(x, d);
        dir = b < bins.binLo[d] ? -1 : (b >= bins.binHi[d] ? +1 : 0);
      }
      const int h0 = hist.hStart[i], h1 = hist.hStart[i + 1];
      if (dir != 0 && dec.neighbor(d, dir) == MPI_PROC_NULL) dir = 0;  // cannot happen
      if (dir == 0) {
        keepRow(i, w, h0, h1, hw);
        ++w;
      } else {
        auto& b = ghosts.sbuf[dir > 0 ? 1 : 0];
        const std::size_t o = b.size();
        b.resize(o + W);
        detail::packRow(p, kOpMigrate, i, nullptr, b.data() + o);
        b.push_back(h1 - h0);
        for (int e = h0; e < h1; ++e) {
          b.push_back(static_cast<double>(hist.hId[static_cast<std::size_t>(e)]));
          for (int k = 0; k < 3; ++k)
            b.push_back(hist.hS[3 * static_cast<std::size_t>(e) + static_cast<std::size_t>(k)]);
        }
      }
    }
    p.nOwned = w;
    hist.truncate(w, hw);
    if (dec.neighbor(d, -1) == MPI_PROC_NULL && dec.neighbor(d, +1) == MPI_PROC_NULL) continue;
    exchange(d, kTagMigCount + 10 * d, false);
    for (int s = 0; s < 2; ++s) {
      const auto& b = ghosts.rbuf[static_cast<std::size_t>(s)];
      std::size_t q = 0;
      while (q < b.size()) {
        const std::size_t i = p.nOwned;
        detail::resizeAll(p, i + 1);
        p.nOwned = i + 1;
        detail::unpackRow(p, kOpMigrate, b.data() + q, i, true);
        const int nh = static_cast<int>(b[q + W]);
        q += W + 1;
        ensure(hist.hId, hist.hId.size() + static_cast<std::size_t>(nh));
        ensure(hist.hS, hist.hS.size() + 3 * static_cast<std::size_t>(nh));
        ensure(hist.hStart, hist.hStart.size() + 1);
        for (int e = 0; e < nh; ++e, q += 4) {
          hist.hId.push_back(static_cast<std::int64_t>(b[q]));
          hist.hS.insert(hist.hS.end(), b.data() + q + 1, b.data() + q + 4);
        }
        hist.hStart.push_back(static_cast<int>(hist.hId.size()));
      }
    }
  }
  comm.raiseIfAny(err);
}

void DemSolver::Impl::buildGhosts() {
  const Int3 coords = dec.coords(), dims = dec.dims();
  const std::size_t W = detail::rowWidth(p, kOpGhostBuild);
  for (int d = 0; d < 3; ++d) {
    const std::size_t nBefore = p.size();
    for (int s = 0; s < 2; ++s) {
      auto& sw = ghosts.swaps[d][static_cast<std::size_t>(s)];
      auto& b = ghosts.sbuf[static_cast<std::size_t>(s)];
      sw.send.clear();
      b.clear();
      sw.shift = 0;
      if (dec.neighbor(d, s == 0 ? -1 : 1) == MPI_PROC_NULL) continue;
      if (bins.periodic[d]) {
        if (s == 0 && coords[d] == 0) sw.shift = bins.L[d];
        if (s == 1 && coords[d] == dims[d] - 1) sw.shift = -bins.L[d];
      }
      const double* x = p.x[d].data();
      const double lim = s == 0 ? bins.lo[d] + rc : bins.hi[d] - rc;
      for (std::size_t i = 0; i < nBefore; ++i)
        if (s == 0 ? x[i] < lim : x[i] >= lim) sw.send.push_back(static_cast<int>(i));
      double shift[3] = {0, 0, 0};
      shift[d] = sw.shift;
      b.resize(sw.send.size() * W);
      detail::packRows(p, kOpGhostBuild, sw.send, shift, b.data());
    }
    if (dec.neighbor(d, -1) == MPI_PROC_NULL && dec.neighbor(d, +1) == MPI_PROC_NULL) {
      for (int s = 0; s < 2; ++s) ghosts.swaps[d][static_cast<std::size_t>(s)].recvCount = 0;
      continue;
    }
    exchange(d, kTagGhostCount + 10 * d, false);
    for (int s = 0; s < 2; ++s) {
      const auto& b = ghosts.rbuf[static_cast<std::size_t>(s)];
      const std::size_t cnt = W > 0 ? b.size() / W : 0;
      const std::size_t start = p.size();
      auto& sw = ghosts.swaps[d][static_cast<std::size_t>(s)];
      sw.recvStart = static_cast<int>(start);
      sw.recvCount = static_cast<int>(cnt);
      detail::resizeAll(p, start + cnt);
      p.nGhost += cnt;
      detail::unpackRows(p, kOpGhostBuild, b.data(), cnt, start, true);
    }
  }
}

void DemSolver::Impl::updateGhosts() {
  const std::size_t W = detail::rowWidth(p, kOpGhostUpdate);
  for (int d = 0; d < 3; ++d) {
    if (dec.neighbor(d, -1) == MPI_PROC_NULL && dec.neighbor(d, +1) == MPI_PROC_NULL) continue;
    for (int s = 0; s < 2; ++s) {
      const auto& sw = ghosts.swaps[d][static_cast<std::size_t>(s)];
      auto& b = ghosts.sbuf[static_cast<std::size_t>(s)];
      double shift[3] = {0, 0, 0};
      shift[d] = sw.shift;
      b.resize(sw.send.size() * W);
      detail::packRows(p, kOpGhostUpdate, sw.send, shift, b.data());
      ghosts.rbuf[static_cast<std::size_t>(s)].resize(static_cast<std::size_t>(sw.recvCount) * W);
    }
    exchange(d, kTagUpdate + 10 * d, true);
    for (int s = 0; s < 2; ++s) {
      const auto& sw = ghosts.swaps[d][static_cast<std::size_t>(s)];
      detail::unpackRows(p, kOpGhostUpdate, ghosts.rbuf[static_cast<std::size_t>(s)].data(),
                         static_cast<std::size_t>(sw.recvCount),
                         static_cast<std::size_t>(sw.recvStart), false);
    }
  }
}

}  // namespace coloc::dem
