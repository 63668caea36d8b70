#include "coloc/coupling/plan.hpp"

#include <algorithm>
#include <cmath>

#include "coloc/core/error.hpp"
#include "coloc/coupling/heat_transfer.hpp"
#include "coloc/coupling/simulation.hpp"
#include "coloc/coupling/transfer.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/box_halo.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {
namespace {

constexpr long long kDouble = sizeof(double);
// Ghost layers: the fluid keeps 2 (fv's kGhost), the coupling's own halo plan 1.
constexpr int kFluidGhost = 2, kCouplingGhost = 1;
// Doubles per row: the DEM's ghost update (its field table's built-in fields in kOpGhostUpdate),
// the proxy transfer's row and the force sent back (coupling/transfer.hpp).
const long long kGhostUpdate =
    static_cast<long long>(dem::rowWidth(dem::ParticleStore{}, dem::kOpGhostUpdate));

/// The widths that depend on the case's physics: heat adds the particle temperature to the DEM's
/// ghost update (its one kOpGhostUpdate extra field, dem/src/heat.cpp), one gather of the fluid's
/// T per heat sub-step (the plan counts one: the report's fluid_heat.substeps_last says how many
/// a step took), and convection one gather of the step's mean T, the temperature and material to
/// the proxy rows, the heat rate to the rows back and two deposited fields (the heat source and
/// its coefficient).
struct Widths {
  long long ghostUpdate = kGhostUpdate, proxyRow = kProxyRowDoubles, forceRow = kForceRowDoubles;
  int deposited = 5, temperatureHalos = 0;
};
Widths widthsOf(const Config& cfg, bool coupled) {
  Widths w;
  if (cfg.boolean("particles.heat")) w.ghostUpdate += 1;
  if (cfg.boolean("fluid.heat")) w.temperatureHalos = 1;
  if (coupled && heatLawFromName(cfg.string("coupling.heat_transfer")) != HeatLaw::None) {
    w.proxyRow += kProxyHeatDoubles;
    w.forceRow += kHeatRowDoubles;
    w.deposited = 7;
    w.temperatureHalos += 1;
  }
  return w;
}

std::size_t k(Traffic t) {
  return static_cast<std::size_t>(t);
}

/// One field layout of a block: owned extent n, ghost g, stagger s (partition/field.hpp).
struct Layout {
  Int3 n{};
  int g = 1;
  Int3 s{0, 0, 0};
  long long extent(int d) const { return n[d] + 2LL * g + s[d]; }
  long long across(int d) const {  // allocated cells of the two other axes
    return extent((d + 1) % 3) * extent((d + 2) % 3);
  }
};

/// HaloPlan's booking for `fields` fields of layout `l` on rank r: gather sends the owned edge
/// (g + s layers on the low side, g on the high), scatterSum sends the ghosts (g low, g + s high);
/// a message per side with a peer other than the rank itself.
void halo(const GlobalGrid& grid, const Blocks& b, int r, const Layout& l, int fields, bool reverse,
          long long times, TrafficCount& out) {
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      const int peer = b.neighbour(grid, r, d, side == 0 ? -1 : 1);
      if (peer < 0 || peer == r) continue;
      const long long layers = (side == 0) != reverse ? l.g + l.s[d] : l.g;
      out.bytes += times * layers * l.across(d) * fields * kDouble;
      out.messages += times;
    }
}

/// Cells of a point, clamped (Decomposition::cellOfPoint).
int cellAlong(const GlobalGrid& g, int d, double x) {
  const double s = (x - g.origin[d]) / g.spacing(d);
  return std::clamp(static_cast<int>(std::floor(s)), 0, g.cells[d] - 1);
}

/// The fluid block's owner of a point (Decomposition::ownerOfPoint); -1 outside.
int fluidOwner(const GlobalGrid& g, const Blocks& b, const double* x) {
  Int3 c{};
  for (int d = 0; d < 3; ++d) {
    double s = (x[d] - g.origin[d]) / g.spacing(d);
    const int n = g.cells[d];
    if (!std::isfinite(s)) return -1;
    if (g.periodic[d]) {
      s = std::fmod(s, static_cast<double>(n));
      if (s < 0) s += n;
    } else if (s < 0.0 || s > static_cast<double>(n)) {
      return -1;
    }
    c[d] = b.blockAlong(d, std::clamp(static_cast<int>(std::floor(s)), 0, n - 1));
  }
  return b.rankOf(c);
}

long long substepsPerStep(const Config& cfg, RunMode mode) {
  switch (mode) {
    case RunMode::FluidOnly:
      return 0;
    case RunMode::ParticlesOnly:
      return std::max<long long>(1, cfg.integer("coupling.dem_substeps"));
    case RunMode::DummyDem:
      // frozen: a sub-step exchanges nothing, except with particles.heat, where it refreshes the
      // ghosts' temperatures (the DEM's ghost update; dem.cpp, frozenSubstep)
      if (!cfg.boolean("particles.heat")) return 0;
      [[fallthrough]];
    case RunMode::Coupled: {
      const long long n = cfg.integer("coupling.dem_substeps");
      if (n > 0) return n;
      return std::max<long long>(
          1, static_cast<long long>(
                 std::floor(cfg.number("fluid.dt") / cfg.number("particles.dt") + 1e-9)));
    }
  }
  return 0;
}

/// Traffic of `times` halo operations of `fields` fields (ghost layers, staggering) on a box
/// layout, as BoxHaloPlan books it: a gather sends, from each owner, the pieces of its
/// neighbours' ghost regions it owns, one message per neighbour; a reverse sum the opposite.
/// Pieces a rank owns itself (periodic images, its own wall ghosts) stay in memory.
void boxHalo(const BoxLayout& L, int ghost, Int3 stagger, int fields, bool reverse, long long times,
             Traffic kind, std::vector<RankPlan>& rank) {
  std::vector<int> peers;
  for (int r = 0; r < L.size(); ++r) {
    peers.clear();
    for (const auto& p : haloPieces(L, r, ghost, stagger)) {
      if (p.owner == r) continue;
      const int sender = reverse ? r : p.owner;
      rank[static_cast<std::size_t>(sender)].perStep[k(kind)].bytes +=
          times * p.src.volume() * fields * kDouble;
      if (std::find(peers.begin(), peers.end(), p.owner) == peers.end()) peers.push_back(p.owner);
    }
    for (int q : peers)
      rank[static_cast<std::size_t>(reverse ? r : q)].perStep[k(kind)].messages += times;
  }
}

/// A layout of tiled boxes (no process grid): one box per rank for both physics.
LayoutPlan planBoxes(const PlanCase& pc, const StrategyInput& in, const StrategyLayout& layout,
                     LayoutPlan out) {
  const Config& cfg = *pc.cfg;
  const GlobalGrid& g = pc.grid;
  const int ranks = out.ranks;
  const bool fluidOn = pc.mode != RunMode::ParticlesOnly;
  const bool demOn = pc.mode != RunMode::FluidOnly;
  const bool coupled = pc.mode == RunMode::Coupled || pc.mode == RunMode::DummyDem;
  const BoxLayout& L = layout.fluid;
  const Widths w = widthsOf(cfg, coupled);
  dem::BinLayout bins;
  try {
    // The boxes under the case's cost, as the bisection measures them (a fluid-only run's boxes
    // were placed on equal cells).
    TiledLayout t;
    t.layout = L;
    TiledOptions opt;
    opt.surfaceCost = cfg.number("partition.cost.halo_cell");
    evaluateBoxes(pc.cost, opt, t);
    out.boxes = L.box;
    out.modelledImbalance = t.imbalance();
    if (t.avgCost > 0)
      out.imbalanceFloor = boxCostFloor(g, pc.cost, std::max(2, in.minCells)) / t.avgCost;
    if (demOn)
      bins = dem::binLayout(cfg, g, L.cutPlanes(), pc.particles.dmax, pc.particles.skin,
                            pc.particles.total);
  } catch (const Error& e) {
    out.error = e.what();
    return out;
  }
  out.substeps = substepsPerStep(cfg, pc.mode);
  out.rank.assign(static_cast<std::size_t>(ranks), RankPlan{});
  for (int r = 0; r < ranks; ++r) {
    auto& R = out.rank[static_cast<std::size_t>(r)];
    R.cells = L.box[static_cast<std::size_t>(r)].volume();
    if (!fluidOn) continue;
    R.ghostCells = haloRemoteCells(L, r, kFluidGhost);
    R.haloNeighbours = static_cast<int>(haloNeighbours(L, r, kFluidGhost).size());
  }
  if (fluidOn) {
    // The schedule of planLayout (fv::FluidSolver::step, Simulation::step).
    auto& rk = out.rank;
    boxHalo(L, kFluidGhost, {0, 0, 0}, 6, false, 1, Traffic::FluidHalo, rk);
    boxHalo(L, kFluidGhost, {0, 0, 0}, 1, false, 1, Traffic::FluidHalo, rk);
    if (w.temperatureHalos > 0)
      boxHalo(L, kFluidGhost, {0, 0, 0}, 1, false, w.temperatureHalos, Traffic::FluidHalo, rk);
    for (int c = 0; c < 3; ++c) {
      Int3 s{0, 0, 0};
      s[c] = 1;
      boxHalo(L, kFluidGhost, s, 1, false, coupled ? 3 : 2, Traffic::FluidHalo, rk);
    }
    if (coupled) {
      boxHalo(L, kFluidGhost, {0, 0, 0}, 3, false, 1, Traffic::FluidHalo, rk);
      boxHalo(L, kCouplingGhost, {0, 0, 0}, w.deposited, true, 1, Traffic::DepositSum, rk);
    }
  }
  const double wc = cfg.number("partition.cost.cell"), wp = cfg.number("partition.cost.particle");
  if (demOn) {
    const std::vector<int> cellOwner = L.ownerMap();
    const auto& X = pc.particles.x;
    const std::size_t N = X[0].size();
    std::vector<std::array<double, 3>> lo(static_cast<std::size_t>(ranks)),
        hi(static_cast<std::size_t>(ranks));
    for (int r = 0; r < ranks; ++r)
      for (int d = 0; d < 3; ++d) {
        const IndexBox& b = L.box[static_cast<std::size_t>(r)];
        lo[static_cast<std::size_t>(r)][d] = bins.lo(g, d, bins.blockBinLo(d, b.lo[d]));
        hi[static_cast<std::size_t>(r)][d] = bins.hi(g, d, bins.blockBinLo(d, b.hi[d]));
      }
    const auto ownerOfCell = [&](const Int3& c) {
      return cellOwner[static_cast<std::size_t>(c[0] + g.cells[0] * (c[1] + g.cells[1] * c[2]))];
    };
    const double rc = pc.particles.range;
    std::vector<std::vector<int>> dests(static_cast<std::size_t>(ranks));
    std::vector<int> cand;
    for (std::size_t i = 0; i < N; ++i) {
      Int3 c{};
      for (int d = 0; d < 3; ++d) c[d] = bins.cellOfBin(d, bins.binOf(g, d, X[d][i]));
      const int q = ownerOfCell(c);
      auto& Q = out.rank[static_cast<std::size_t>(q)];
      ++Q.particles;
      if (coupled) Q.perStep[k(Traffic::ForceHandover)].bytes += w.forceRow * kDouble;
      // Ghosts: every box (periodic images included) whose range-widened bounds hold the
      // particle; the owner's own image at shift 0 is the particle itself.
      std::array<std::array<double, 3>, 3> shifts{};
      std::array<int, 3> nShift{};
      for (int d = 0; d < 3; ++d) {
        shifts[d][nShift[d]++] = 0.0;
        if (!g.periodic[d]) continue;
        if (X[d][i] < g.origin[d] + rc) shifts[d][nShift[d]++] = g.length[d];
        if (X[d][i] >= g.origin[d] + g.length[d] - rc) shifts[d][nShift[d]++] = -g.length[d];
      }
      for (int a = 0; a < nShift[0]; ++a)
        for (int b = 0; b < nShift[1]; ++b)
          for (int e = 0; e < nShift[2]; ++e) {
            const double y[3] = {X[0][i] + shifts[0][a], X[1][i] + shifts[1][b],
                                 X[2][i] + shifts[2][e]};
            const bool image = a + b + e > 0;
            Int3 c0{}, c1{};
            for (int d = 0; d < 3; ++d) {
              c0[d] = cellAlong(g, d, y[d] - rc);
              c1[d] = cellAlong(g, d, y[d] + rc);
            }
            cand.clear();
            for (int kk = c0[2]; kk <= c1[2]; ++kk)
              for (int jj = c0[1]; jj <= c1[1]; ++jj)
                for (int ii = c0[0]; ii <= c1[0]; ++ii) {
                  const int r = ownerOfCell({ii, jj, kk});
                  if (std::find(cand.begin(), cand.end(), r) == cand.end()) cand.push_back(r);
                }
            for (int r : cand) {
              if (r == q && !image) continue;
              bool in = true;
              for (int d = 0; d < 3 && in; ++d)
                in = y[d] >= lo[static_cast<std::size_t>(r)][d] - rc &&
                     y[d] < hi[static_cast<std::size_t>(r)][d] + rc;
              if (!in) continue;
              ++out.rank[static_cast<std::size_t>(r)].demGhosts;
              if (r == q) continue;
              Q.perStep[k(Traffic::DemGhost)].bytes += out.substeps * w.ghostUpdate * kDouble;
              auto& dq = dests[static_cast<std::size_t>(q)];
              if (std::find(dq.begin(), dq.end(), r) == dq.end()) dq.push_back(r);
            }
          }
    }
    for (int q = 0; q < ranks; ++q)
      out.rank[static_cast<std::size_t>(q)].perStep[k(Traffic::DemGhost)].messages +=
          out.substeps * static_cast<long long>(dests[static_cast<std::size_t>(q)].size());
  }
  double sum = 0, mx = 0;
  for (auto& R : out.rank) {
    R.cost = (fluidOn ? wc * static_cast<double>(R.cells) : 0.0) +
             (demOn ? wp * static_cast<double>(R.particles) : 0.0);
    sum += R.cost;
    mx = std::max(mx, R.cost);
  }
  out.imbalance = sum > 0 ? mx / (sum / ranks) : 1.0;
  return out;
}

}  // namespace

PlanCase planCase(const Config& cfg) {
  PlanCase pc;
  pc.cfg = &cfg;
  pc.grid = gridFromConfig(cfg);
  pc.mode = runMode(cfg);
  if (pc.mode != RunMode::FluidOnly) pc.particles = dem::caseParticles(cfg, pc.grid);
  const auto& g = pc.grid;
  const std::size_t cells = static_cast<std::size_t>(g.cellCount());
  // cellCosts' arithmetic: the particle weight added once per particle, then the cell weight.
  const double perCell = cfg.number("partition.cost.cell");
  const double perParticle = cfg.number("partition.cost.particle");
  pc.cost.assign(cells, 0.0);
  pc.count.assign(cells, 0.0);
  const auto& x = pc.particles.x;
  for (std::size_t i = 0; i < x[0].size(); ++i) {
    const std::size_t c = static_cast<std::size_t>(
        cellAlong(g, 0, x[0][i]) +
        g.cells[0] * (cellAlong(g, 1, x[1][i]) + g.cells[1] * cellAlong(g, 2, x[2][i])));
    pc.cost[c] += perParticle;
    pc.count[c] += 1.0;
  }
  for (double& c : pc.cost) c += perCell;
  return pc;
}

namespace {

/// A process-grid layout: the fluid's blocks, and the particles' (their own in independent
/// partitions).
LayoutPlan planBlocks(const PlanCase& pc, const StrategyLayout& layout, LayoutPlan out) {
  const Config& cfg = *pc.cfg;
  const GlobalGrid& g = pc.grid;
  const int ranks = out.ranks;
  const bool fluidOn = pc.mode != RunMode::ParticlesOnly;
  const bool demOn = pc.mode != RunMode::FluidOnly;
  const bool coupled = pc.mode == RunMode::Coupled || pc.mode == RunMode::DummyDem;
  const bool independent = layout.particleBlocks.has_value();
  const Widths w = widthsOf(cfg, coupled);
  dem::BinLayout bins;
  try {
    out.fluid = *layout.fluidBlocks;
    out.particles = layout.particleBlocks ? *layout.particleBlocks : out.fluid;
    if (demOn)
      bins = dem::binLayout(cfg, g, out.particles.cuts, pc.particles.dmax, pc.particles.skin,
                            pc.particles.total);
  } catch (const Error& e) {
    out.error = e.what();
    return out;
  }
  out.substeps = substepsPerStep(cfg, pc.mode);
  out.rank.assign(static_cast<std::size_t>(ranks), RankPlan{});
  const Blocks& F = out.fluid;
  const Blocks& D = out.particles;

  // Fluid work and halos.
  for (int r = 0; r < ranks; ++r) {
    auto& R = out.rank[static_cast<std::size_t>(r)];
    const Int3 lo = F.lo(r), hi = F.hi(r);
    const Int3 n{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    R.cells = 1LL * n[0] * n[1] * n[2];
    if (!fluidOn) continue;
    auto& fh = R.perStep[k(Traffic::FluidHalo)];
    const Layout cell{n, kFluidGhost, {0, 0, 0}};
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) {
        const int peer = F.neighbour(g, r, d, side == 0 ? -1 : 1);
        if (peer >= 0 && peer != r) R.ghostCells += 1LL * kFluidGhost * cell.across(d);
      }
    // fv::FluidSolver::step: eps, eps_old, K, K u_p (6 fields); u* on the faces (each component
    // alone) before the predictor when stale and before the pressure equation; p after it.
    // Coupled, the step is followed by cellVelocity (faces again) and pressureGradient (3).
    halo(g, F, r, cell, 6, false, 1, fh);
    halo(g, F, r, cell, 1, false, 1, fh);
    if (w.temperatureHalos > 0) halo(g, F, r, cell, 1, false, w.temperatureHalos, fh);
    const int faceGathers = coupled ? 3 : 2;
    for (int c = 0; c < 3; ++c) {
      Layout face = cell;
      face.s[c] = 1;
      halo(g, F, r, face, 1, false, faceGathers, fh);
    }
    if (coupled) {
      halo(g, F, r, cell, 3, false, 1, fh);
      const Layout one{n, kCouplingGhost, {0, 0, 0}};
      // (No Traffic::CouplingHalo: the coupling reads the fluid's eps, gathered above.)
      halo(g, F, r, one, w.deposited, true, 1, R.perStep[k(Traffic::DepositSum)]);
    }
  }
  if (!demOn) {
    double sum = 0, mx = 0;
    for (auto& R : out.rank) {
      R.cost = cfg.number("partition.cost.cell") * static_cast<double>(R.cells);
      sum += R.cost;
      mx = std::max(mx, R.cost);
    }
    out.imbalance = sum > 0 ? mx / (sum / ranks) : 1.0;
    return out;
  }

  // Particles: owners on the DEM's blocks (its bins), fluid owners for the proxies.
  const auto& X = pc.particles.x;
  const std::size_t N = X[0].size();
  std::vector<int> owner(N);
  std::vector<long long> start(static_cast<std::size_t>(ranks) + 1, 0);
  for (std::size_t i = 0; i < N; ++i) {
    Int3 blk{};
    for (int d = 0; d < 3; ++d)
      blk[d] = D.blockAlong(d, bins.cellOfBin(d, bins.binOf(g, d, X[d][i])));
    owner[i] = D.rankOf(blk);
    ++start[static_cast<std::size_t>(owner[i]) + 1];
  }
  for (int r = 0; r < ranks; ++r) {
    out.rank[static_cast<std::size_t>(r)].particles = start[static_cast<std::size_t>(r) + 1];
    start[static_cast<std::size_t>(r) + 1] += start[static_cast<std::size_t>(r)];
  }
  // Positions bucketed by owner: owned first, ghosts appended sweep by sweep (buildGhosts).
  std::vector<std::array<std::vector<double>, 3>> P(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r)
    for (auto& v : P[static_cast<std::size_t>(r)])
      v.reserve(static_cast<std::size_t>(out.rank[static_cast<std::size_t>(r)].particles));
  for (std::size_t i = 0; i < N; ++i)
    for (int d = 0; d < 3; ++d) P[static_cast<std::size_t>(owner[i])][d].push_back(X[d][i]);

  if (coupled) {
    if (!independent) {
      for (auto& R : out.rank)
        R.perStep[k(Traffic::ForceHandover)].bytes += R.particles * w.forceRow * kDouble;
    } else {
      // Rows from DEM rank a to fluid rank b, and the forces back (booked by b).
      std::vector<std::vector<std::pair<int, long long>>> to(static_cast<std::size_t>(ranks));
      for (std::size_t i = 0; i < N; ++i) {
        const double xi[3] = {X[0][i], X[1][i], X[2][i]};
        const int b = std::max(fluidOwner(g, F, xi), 0);
        auto& row = to[static_cast<std::size_t>(owner[i])];
        auto it = std::find_if(row.begin(), row.end(), [b](const auto& q) { return q.first == b; });
        if (it == row.end())
          row.emplace_back(b, 1);
        else
          ++it->second;
      }
      for (int a = 0; a < ranks; ++a)
        for (const auto& [b, c] : to[static_cast<std::size_t>(a)]) {
          auto& A = out.rank[static_cast<std::size_t>(a)];
          auto& B = out.rank[static_cast<std::size_t>(b)];
          B.proxies += c;
          if (a == b) {
            A.perStep[k(Traffic::ForceHandover)].bytes += c * (w.proxyRow + w.forceRow) * kDouble;
          } else {
            A.perStep[k(Traffic::Proxy)].bytes += c * w.proxyRow * kDouble;
            ++A.perStep[k(Traffic::Proxy)].messages;
            B.perStep[k(Traffic::Proxy)].bytes += c * w.forceRow * kDouble;
            ++B.perStep[k(Traffic::Proxy)].messages;
          }
        }
    }
  }

  // DEM ghosts: three staged sweeps; along d a rank sends the particles (owned and ghosts of the
  // earlier sweeps) within the interaction range of its low / high bin face.
  const double rc = pc.particles.range;
  std::vector<std::array<std::vector<double>, 3>> pending(static_cast<std::size_t>(ranks));
  std::vector<std::size_t> before(static_cast<std::size_t>(ranks));
  for (int d = 0; d < 3; ++d) {
    for (int r = 0; r < ranks; ++r)
      before[static_cast<std::size_t>(r)] = P[static_cast<std::size_t>(r)][0].size();
    for (int r = 0; r < ranks; ++r) {
      const int nLo = D.neighbour(g, r, d, -1), nHi = D.neighbour(g, r, d, +1);
      if (nLo < 0 && nHi < 0) continue;
      const Int3 c = D.coordsOf(r);
      const double lo = bins.lo(g, d, bins.blockBinLo(d, D.lo(r)[d]));
      const double hi = bins.hi(g, d, bins.blockBinLo(d, D.hi(r)[d]));
      auto& R = out.rank[static_cast<std::size_t>(r)];
      const auto& Q = P[static_cast<std::size_t>(r)];
      long long sentLo = 0;
      for (int s = 0; s < 2; ++s) {
        const int peer = s == 0 ? nLo : nHi;
        if (peer < 0) continue;
        double shift = 0;
        if (g.periodic[d]) {
          if (s == 0 && c[d] == 0) shift = g.length[d];
          if (s == 1 && c[d] == D.dims[d] - 1) shift = -g.length[d];
        }
        const double lim = s == 0 ? lo + rc : hi - rc;
        long long sent = 0;
        auto& dst = pending[static_cast<std::size_t>(peer)];
        for (std::size_t i = 0; i < before[static_cast<std::size_t>(r)]; ++i) {
          const double x = Q[d][i];
          if (s == 0 ? x < lim : x >= lim) {
            ++sent;
            for (int a = 0; a < 3; ++a) dst[a].push_back(Q[a][i] + (a == d ? shift : 0.0));
          }
        }
        if (peer != r) {
          auto& t = R.perStep[k(Traffic::DemGhost)];
          t.bytes += out.substeps * sent * w.ghostUpdate * kDouble;
          // one message per neighbour with rows (the axis' plan: both faces' rows in one message
          // when both go to one rank; nothing to a neighbour without rows)
          if (sent > 0 && !(s == 1 && nLo == nHi && sentLo > 0)) t.messages += out.substeps;
        }
        if (s == 0) sentLo = sent;
      }
    }
    for (int r = 0; r < ranks; ++r) {
      auto& src = pending[static_cast<std::size_t>(r)];
      auto& Q = P[static_cast<std::size_t>(r)];
      out.rank[static_cast<std::size_t>(r)].demGhosts += static_cast<long long>(src[0].size());
      for (int a = 0; a < 3; ++a) {
        Q[a].insert(Q[a].end(), src[a].begin(), src[a].end());
        src[a].clear();
        src[a].shrink_to_fit();
      }
    }
  }

  double sum = 0, mx = 0;
  const double wc = cfg.number("partition.cost.cell"), wp = cfg.number("partition.cost.particle");
  for (auto& R : out.rank) {
    R.cost =
        (fluidOn ? wc * static_cast<double>(R.cells) : 0.0) + wp * static_cast<double>(R.particles);
    sum += R.cost;
    mx = std::max(mx, R.cost);
  }
  out.imbalance = sum > 0 ? mx / (sum / ranks) : 1.0;
  return out;
}

}  // namespace

LayoutPlan planLayout(const PlanCase& pc, const PartitionStrategy& strategy, int ranks) {
  LayoutPlan out;
  out.strategy = strategy.name();
  out.ranks = ranks;
  StrategyInput in;
  StrategyLayout layout;
  try {
    in = strategyInput(*pc.cfg, ranks);
    layout = strategy.layoutFor(
        pc.mode, in, CellWork{pc.cost, pc.count, pc.cfg->number("partition.cost.halo_cell")});
  } catch (const Error& e) {
    out.error = e.what();
    return out;
  }
  return layout.isGrid() ? planBlocks(pc, layout, std::move(out))
                         : planBoxes(pc, in, layout, std::move(out));
}

LayoutPlan planLayout(const PlanCase& pc, const std::string& strategy, int ranks) {
  return planLayout(pc, PartitionStrategy::named(strategy), ranks);
}

}  // namespace coloc::coupling
