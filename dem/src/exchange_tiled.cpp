// dem/src/exchange_tiled.cpp — the particle exchange on a tiled layout (general boxes,
// Decomposition::isTiled): no process grid, so no staged sweeps. Migration is one exchange: a
// particle leaving its box goes straight to the owner of its (periodically wrapped) position. A
// ghost build sends every owned particle to each target (a box near this one, or a periodic
// image of one) whose bounds widened by the interaction range hold it, the position shifted by
// the image's period: on a process grid that is the set of ghosts the staged sweeps deliver
// (faces, edges, corners). The plan of the build is reused by the updates (same rows, same order)
// until the next rebuild.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "exchange.hpp"
#include "rows.hpp"

namespace coloc::dem::detail {

namespace {

class TiledExchange final : public ParticleExchange {
 public:
  TiledExchange(const ExchangeContext& c, const BinLayout& b);
  void migrate() override;
  void buildGhosts() override;
  void updateGhosts() override;
  std::size_t bytes() const override {
    return cap(rbuf_) + cap(rank_) + cap(index_) + cap(targets_) + cap(near_) + cap(runs_) +
           cap(cand_) + cap(dest_) + cap(at_);
  }

 private:
  // A target is a box whose bins lie within one bin (the interaction range) of this box's, or a
  // periodic image of one (this box's own images included): an owned particle whose position +
  // shift lies in [lo, hi) (the target's bounds widened by the range) is a ghost there. Targets
  // are ordered by rank, then image, so the ghosts of a build arrive by source rank, target
  // image, source row: the same order on every run.
  struct Target {
    int rank = 0;
    std::array<double, 3> shift{}, lo{}, hi{};
  };
  /// The build listed its rows target by target, targets by rank: the plan's export order
  /// (grouped by rank, stable) is that order, so each target's rows are one run with one shift.
  PlanTraffic forwardRows(unsigned op, std::size_t W);
  /// The count messages of a plan build: one to each near rank but this one.
  long long countMessages() const {
    const bool self = std::binary_search(near_.begin(), near_.end(), c_.dec.rank());
    return static_cast<long long>(near_.size()) - (self ? 1 : 0);
  }

  std::vector<Target> targets_;
  std::vector<int> near_;  // the targets' ranks, distinct, ascending (this rank if it has images)
  std::vector<int> runs_;  // rows per target of the last ghost build (consecutive in the plan)
  std::vector<int> cand_;  // scratch: owned particles within the range of a face of this box
  std::vector<int> dest_;  // scratch: destination of every owned particle (migration)
  std::vector<std::size_t> at_;  // scratch: next export position per rank (migration)
  CommPlan box_;                 // ghost build / update on the targets
};

TiledExchange::TiledExchange(const ExchangeContext& c, const BinLayout& b) : ParticleExchange(c) {
  const Decomposition& dec = c.dec;
  const Bins& bins = c.bins;
  const auto& grid = dec.grid();
  std::vector<Int3> lo, hi;
  dec.boxes(lo, hi);
  // bins a ghost may lie away from the box (the range is at most one bin when bins are legal;
  // wider bins of a case without particles still give a symmetric relation)
  std::array<long long, 3> reach{};
  for (int d = 0; d < 3; ++d)
    reach[d] = std::max(1LL, static_cast<long long>(std::ceil(c.rc / bins.bs[d])));
  const int me = dec.rank();
  for (int r = 0; r < dec.size(); ++r) {
    const auto ru = static_cast<std::size_t>(r);
    std::array<long long, 3> rLo{}, rHi{};
    for (int d = 0; d < 3; ++d) {
      rLo[d] = b.blockBinLo(d, lo[ru][d]);
      rHi[d] = b.blockBinLo(d, hi[ru][d]);
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
          Target t;
          t.rank = r;
          for (int d = 0; d < 3; ++d) {
            t.shift[d] = k[d] * bins.L[d];
            t.lo[d] = b.lo(grid, d, rLo[d]) - c.rc;
            t.hi[d] = b.hi(grid, d, rHi[d]) + c.rc;
          }
          targets_.push_back(t);
          any = true;
        }
    if (any) near_.push_back(r);
  }
}

void TiledExchange::migrate() {
  ParticleStore& p = c_.p;
  const Bins& bins = c_.bins;
  p.nGhost = 0;
  resizeAll(p, p.nOwned);
  const std::size_t W = rowWidth(p, kOpMigrate);
  const std::size_t n = p.nOwned;
  const int me = c_.dec.rank();
  const auto size = static_cast<std::size_t>(c_.comm.size());
  // pass 1: wrap, destination (the owner rule of the bins: bins.owns here, the tree elsewhere),
  // and the doubles going to each rank
  ensure(dest_, n);
  dest_.resize(n);
  counts_.assign(size, 0);
  for (std::size_t i = 0; i < n; ++i) {
    bool lost = false;
    for (int d = 0; d < 3; ++d) lost = crossAxis(i, d) == kLost || lost;
    const double x[3] = {p.x[0][i], p.x[1][i], p.x[2][i]};
    int to = lost || bins.owns(x) ? me : bins.ownerRank(c_.dec, x);
    if (to != me && !std::binary_search(near_.begin(), near_.end(), to)) {
      fail([&] {
        return fmt::format(
            "particle {} moved beyond the boxes next to rank {}'s between two neighbour "
            "rebuilds{} (x = {:.4g}, {:.4g}, {:.4g}): the run blew up (time step too large, or "
            "a NaN in the forces)",
            p.id[i], me, c_.where(), x[0], x[1], x[2]);
      });
      to = me;
    }
    dest_[i] = to;
    if (to != me) counts_[static_cast<std::size_t>(to)] += static_cast<int>(migrantLength(i, W));
  }
  const double t0 = c_.comm.wtime();
  mig_.rebuildFromCounts(c_.comm, counts_, near_);
  const std::span<double> out = mig_.packBuffer(1);
  at_.resize(size);
  for (std::size_t r = 0; r < size; ++r)
    at_[r] = static_cast<std::size_t>(mig_.exportOffset(static_cast<int>(r)));
  // pass 2: leavers packed by destination (in row order), the others kept in place
  std::size_t w = 0;
  int hw = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (dest_[i] == me) {
      keep(i, w, hw);
      ++w;
    } else {
      std::size_t& at = at_[static_cast<std::size_t>(dest_[i])];
      const std::size_t len = migrantLength(i, W);
      packMigrant(i, W, out.subspan(at, len));
      at += len;
    }
  }
  p.nOwned = w;
  c_.hist.truncate(w, hw);
  rbuf_.resize(mig_.importCount());
  const PlanTraffic t = mig_.forwardPacked(1, rbuf_);
  book(c_.timers, t, countMessages(), c_.comm.wtime() - t0, Traffic::DemMigrate);
  // arrivals by source rank, ascending, each in its source's row order
  unpackMigrants(rbuf_, W);
  raiseFailure();
}

PlanTraffic TiledExchange::forwardRows(unsigned op, std::size_t W) {
  const std::span<double> out = box_.packBuffer(static_cast<int>(W));
  const auto idx = box_.exportIndex();
  std::size_t k = 0;
  for (std::size_t t = 0; t < targets_.size(); ++t) {
    const auto c = static_cast<std::size_t>(runs_[t]);
    packRows(c_.p, op, idx.subspan(k, c), targets_[t].shift.data(), out.subspan(k * W).data());
    k += c;
  }
  rbuf_.resize(box_.importCount() * W);
  return box_.forwardPacked(static_cast<int>(W), rbuf_);
}

void TiledExchange::buildGhosts() {
  ParticleStore& p = c_.p;
  const Bins& bins = c_.bins;
  const double rc = c_.rc;
  const std::size_t n = p.nOwned;
  // only a particle within the range of a face of this box can lie near another box (or image)
  cand_.clear();
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      if (p.x[d][i] < bins.lo[d] + rc || p.x[d][i] >= bins.hi[d] - rc) {
        ensure(cand_, cand_.size() + 1);
        cand_.push_back(static_cast<int>(i));
        break;
      }
  rank_.clear();
  index_.clear();
  runs_.assign(targets_.size(), 0);
  for (std::size_t t = 0; t < targets_.size(); ++t) {
    const Target& tg = targets_[t];
    for (const int c : cand_) {
      const auto i = static_cast<std::size_t>(c);
      bool in = true;
      for (std::size_t d = 0; d < 3 && in; ++d) {
        const double y = p.x[d][i] + tg.shift[d];
        in = y >= tg.lo[d] && y < tg.hi[d];
      }
      if (!in) continue;
      ensure(rank_, rank_.size() + 1);
      ensure(index_, index_.size() + 1);
      rank_.push_back(tg.rank);
      index_.push_back(c);
      ++runs_[t];
    }
  }
  const std::size_t W = rowWidth(p, kOpGhostBuild);
  const double t0 = c_.comm.wtime();
  box_.rebuild(c_.comm, rank_, index_, near_);
  const PlanTraffic t = forwardRows(kOpGhostBuild, W);
  book(c_.timers, t, countMessages(), c_.comm.wtime() - t0, Traffic::DemGhost);
  // the ghosts by source rank, target image, source row (the plan's import order)
  const std::size_t start = p.size(), cnt = box_.importCount();
  resizeAll(p, start + cnt);
  p.nGhost += cnt;
  unpackRows(p, kOpGhostBuild, rbuf_.data(), cnt, start, true);
}

void TiledExchange::updateGhosts() {
  const std::size_t W = rowWidth(c_.p, kOpGhostUpdate);
  const double t0 = c_.comm.wtime();
  const PlanTraffic t = forwardRows(kOpGhostUpdate, W);
  book(c_.timers, t, 0, c_.comm.wtime() - t0, Traffic::DemGhost);
  unpackRows(c_.p, kOpGhostUpdate, rbuf_.data(), box_.importCount(), c_.p.nOwned, false);
}

}  // namespace

std::unique_ptr<ParticleExchange> tiledExchange(const ExchangeContext& c, const BinLayout& b) {
  return std::make_unique<TiledExchange>(c, b);
}

}  // namespace coloc::dem::detail
