// dem/src/exchange_grid.cpp — the particle exchange on a process grid: migration in three sweeps
// (x, then y, then z; a particle crossing an edge or a corner moves one face per sweep), and the
// ghosts in three sweeps whose sends include the ghosts of the sweeps before (edges, corners).
// Per axis, the send lists of the two faces and the CommPlan built from them at each ghost build
// are reused by the ghost updates between rebuilds (no count exchange then); migration rebuilds
// one plan per sweep. When both faces of an axis go to one rank (two blocks, or a periodic axis of
// one block), the low face's rows come first in the plan's block of that rank.
#include <algorithm>
#include <array>
#include <span>
#include <string>
#include <vector>

#include "exchange.hpp"
#include "rows.hpp"

namespace coloc::dem::detail {

namespace {

class GridExchange final : public ParticleExchange {
 public:
  explicit GridExchange(const ExchangeContext& c);
  void migrate() override;
  void buildGhosts() override;
  void updateGhosts() override;
  std::size_t bytes() const override;

 private:
  /// Where the ghosts of one sweep come from: `count` rows at import row `from` of the axis'
  /// plan become particles `at`, ... (rows from the high neighbour first, then the low one).
  struct Segment {
    std::size_t from = 0, count = 0, at = 0;
  };
  struct Axis {
    std::array<int, 2> to{};      // the neighbour across the low / high face (MPI_PROC_NULL: none)
    std::array<int, 2> nb{};      // the distinct neighbours (nn of them; this rank when the axis is
    int nn = 0;                   // periodic over one block)
    long long countMessages = 0;  // of a plan build: nn, this rank left out
    std::array<std::vector<int>, 2> send;  // the ghost rows of each face
    std::array<double, 2> shift{};         // added along the axis (periodic faces)
    CommPlan plan;                         // ghost build / update
    std::array<Segment, 2> seg;            // the imports of the last build
    std::size_t nSeg = 0;
    std::span<const int> neighbours() const { return std::span<const int>(nb).first(nn); }
  };

  /// First export item of face s in a plan grouped by rank: the block of its neighbour, the low
  /// face first when both faces go to one rank (`lowItems`: the low face's).
  static std::size_t faceOffset(const CommPlan& plan, const Axis& ax, std::size_t s,
                                std::size_t lowItems) {
    const auto o = static_cast<std::size_t>(plan.exportOffset(ax.to[s]));
    return o + (s == 1 && ax.to[0] == ax.to[1] ? lowItems : 0);
  }
  /// The imports of `plan` from the two neighbours along the axis as segments placed from `at`
  /// on: the high neighbour's, then the low one's (the order of the face exchanges; once when
  /// both are one rank); returns how many.
  static std::size_t importSegments(const CommPlan& plan, const Axis& ax,
                                    std::array<Segment, 2>& seg, std::size_t at);
  /// Both faces' rows of axis d (operation op, W doubles, periodic shift applied) packed in
  /// place into the axis' plan buffer, then sent; what arrives lands in rbuf_.
  PlanTraffic forwardRows(Axis& ax, int d, unsigned op, std::size_t W);

  std::array<Axis, 3> axis_;
  std::array<std::vector<double>, 2> sbuf_;  // migration rows per face
};

GridExchange::GridExchange(const ExchangeContext& c) : ParticleExchange(c) {
  for (int d = 0; d < 3; ++d) {
    Axis& ax = axis_[static_cast<std::size_t>(d)];
    ax.to = {c.dec.neighbour(d, -1), c.dec.neighbour(d, +1)};
    for (const int r : ax.to)
      if (r != MPI_PROC_NULL && (ax.nn == 0 || ax.nb[0] != r))
        ax.nb[static_cast<std::size_t>(ax.nn++)] = r;
    ax.countMessages = ax.nn - (ax.nn > 0 && ax.nb[0] == c.dec.rank() ? 1 : 0);
  }
}

std::size_t GridExchange::importSegments(const CommPlan& plan, const Axis& ax,
                                         std::array<Segment, 2>& seg, std::size_t at) {
  const int lo = ax.to[0], hi = ax.to[1];
  std::size_t n = 0;
  for (const int r : {hi, lo}) {
    if (r == MPI_PROC_NULL || (n == 1 && r == hi)) continue;  // both faces to one rank: once
    const auto count = static_cast<std::size_t>(plan.importsFrom(r));
    seg[n++] = {static_cast<std::size_t>(plan.importOffset(r)), count, at};
    at += count;
  }
  return n;
}

void GridExchange::migrate() {
  ParticleStore& p = c_.p;
  p.nGhost = 0;
  resizeAll(p, p.nOwned);
  // a migrating particle: its row of the field table (kOpMigrate), its history count, then
  // (partner id, shear 3) per history
  const std::size_t W = rowWidth(p, kOpMigrate);
  for (int d = 0; d < 3; ++d) {
    const Axis& ax = axis_[static_cast<std::size_t>(d)];
    for (auto& b : sbuf_) b.clear();
    const std::size_t n = p.nOwned;
    std::size_t w = 0;
    int hw = 0;
    for (std::size_t i = 0; i < n; ++i) {
      int dir = crossAxis(i, d);
      if (dir == kLost) dir = 0;
      const std::size_t s = dir > 0 ? 1 : 0;
      if (dir != 0 && ax.to[s] == MPI_PROC_NULL) dir = 0;  // cannot happen
      if (dir == 0) {
        keep(i, w, hw);
        ++w;
      } else {
        auto& b = sbuf_[s];
        const std::size_t o = b.size();
        b.resize(o + migrantLength(i, W));
        packMigrant(i, W, std::span<double>(b).subspan(o));
      }
    }
    p.nOwned = w;
    c_.hist.truncate(w, hw);
    if (ax.nn == 0) continue;
    // the two faces' rows through one plan whose items are the doubles of the rows (their
    // lengths vary with the histories); the counts go to the neighbours only
    const double t0 = c_.comm.wtime();
    counts_.assign(static_cast<std::size_t>(c_.comm.size()), 0);
    for (std::size_t s = 0; s < 2; ++s)
      if (ax.to[s] != MPI_PROC_NULL)  // a face without a neighbour has no rows (dir = 0 above)
        counts_[static_cast<std::size_t>(ax.to[s])] += static_cast<int>(sbuf_[s].size());
    mig_.rebuildFromCounts(c_.comm, counts_, ax.neighbours());
    const std::span<double> out = mig_.packBuffer(1);
    for (std::size_t s = 0; s < 2; ++s)
      if (ax.to[s] != MPI_PROC_NULL)
        std::ranges::copy(sbuf_[s], out.begin() + static_cast<std::ptrdiff_t>(
                                                      faceOffset(mig_, ax, s, sbuf_[0].size())));
    rbuf_.resize(mig_.importCount());
    const PlanTraffic t = mig_.forwardPacked(1, rbuf_);
    book(c_.timers, t, ax.countMessages, c_.comm.wtime() - t0, Traffic::DemMigrate);
    std::array<Segment, 2> seg;
    const std::size_t ns = importSegments(mig_, ax, seg, 0);
    const std::span<const double> in(rbuf_);
    for (std::size_t g = 0; g < ns; ++g) unpackMigrants(in.subspan(seg[g].from, seg[g].count), W);
  }
  raiseFailure();
}

PlanTraffic GridExchange::forwardRows(Axis& ax, int d, unsigned op, std::size_t W) {
  const std::span<double> out = ax.plan.packBuffer(static_cast<int>(W));
  for (std::size_t s = 0; s < 2; ++s) {
    if (ax.to[s] == MPI_PROC_NULL) continue;
    double shift[3] = {0, 0, 0};
    shift[d] = ax.shift[s];
    const std::size_t at = faceOffset(ax.plan, ax, s, ax.send[0].size());
    packRows(c_.p, op, ax.send[s], shift, out.subspan(at * W).data());
  }
  rbuf_.resize(ax.plan.importCount() * W);
  return ax.plan.forwardPacked(static_cast<int>(W), rbuf_);
}

void GridExchange::buildGhosts() {
  ParticleStore& p = c_.p;
  const Bins& bins = c_.bins;
  const Int3 coords = c_.dec.coords(), dims = c_.dec.dims();
  const std::size_t W = rowWidth(p, kOpGhostBuild);
  for (int d = 0; d < 3; ++d) {
    Axis& ax = axis_[static_cast<std::size_t>(d)];
    const std::size_t nBefore = p.size();  // the ghosts of the sweeps before too
    rank_.clear();
    index_.clear();
    for (std::size_t s = 0; s < 2; ++s) {
      auto& send = ax.send[s];
      send.clear();
      ax.shift[s] = 0;
      if (ax.to[s] == MPI_PROC_NULL) continue;
      if (bins.periodic[d]) {
        if (s == 0 && coords[d] == 0) ax.shift[s] = bins.L[d];
        if (s == 1 && coords[d] == dims[d] - 1) ax.shift[s] = -bins.L[d];
      }
      const double* x = p.x[d].data();
      const double lim = s == 0 ? bins.lo[d] + c_.rc : bins.hi[d] - c_.rc;
      for (std::size_t i = 0; i < nBefore; ++i)
        if (s == 0 ? x[i] < lim : x[i] >= lim) send.push_back(static_cast<int>(i));
      rank_.insert(rank_.end(), send.size(), ax.to[s]);
      index_.insert(index_.end(), send.begin(), send.end());
    }
    ax.nSeg = 0;
    if (ax.nn == 0) continue;
    // one plan per axis from the rows' destinations (counts to the two neighbours only), kept
    // for the updates
    const double t0 = c_.comm.wtime();
    ax.plan.rebuild(c_.comm, rank_, index_, ax.neighbours());
    const PlanTraffic t = forwardRows(ax, d, kOpGhostBuild, W);
    book(c_.timers, t, ax.countMessages, c_.comm.wtime() - t0, Traffic::DemGhost);
    const std::size_t start = p.size(), cnt = ax.plan.importCount();
    ax.nSeg = importSegments(ax.plan, ax, ax.seg, start);
    resizeAll(p, start + cnt);
    p.nGhost += cnt;
    for (std::size_t g = 0; g < ax.nSeg; ++g) {
      const Segment& sg = ax.seg[g];
      unpackRows(p, kOpGhostBuild, rbuf_.data() + sg.from * W, sg.count, sg.at, true);
    }
  }
}

void GridExchange::updateGhosts() {
  const std::size_t W = rowWidth(c_.p, kOpGhostUpdate);
  for (int d = 0; d < 3; ++d) {
    Axis& ax = axis_[static_cast<std::size_t>(d)];
    if (ax.nSeg == 0) continue;
    const double t0 = c_.comm.wtime();
    const PlanTraffic t = forwardRows(ax, d, kOpGhostUpdate, W);
    book(c_.timers, t, 0, c_.comm.wtime() - t0, Traffic::DemGhost);
    for (std::size_t g = 0; g < ax.nSeg; ++g) {
      const Segment& sg = ax.seg[g];
      unpackRows(c_.p, kOpGhostUpdate, rbuf_.data() + sg.from * W, sg.count, sg.at, false);
    }
  }
}

std::size_t GridExchange::bytes() const {
  std::size_t b = cap(sbuf_[0]) + cap(sbuf_[1]) + cap(rbuf_) + cap(rank_) + cap(index_);
  for (const Axis& ax : axis_)
    for (const auto& s : ax.send) b += cap(s);
  return b;
}

}  // namespace

std::unique_ptr<ParticleExchange> gridExchange(const ExchangeContext& c) {
  return std::make_unique<GridExchange>(c);
}

}  // namespace coloc::dem::detail
