#include "coloc/partition/balance.hpp"

#include <fmt/format.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "coloc/core/error.hpp"
#include "prefix_sum.hpp"

namespace coloc {
namespace {

using detail::PrefixSum;

double maxBlock(const PrefixSum& ps, const std::array<std::vector<int>, 3>& c) {
  double worst = 0;
  for (std::size_t a = 0; a + 1 < c[0].size(); ++a)
    for (std::size_t b = 0; b + 1 < c[1].size(); ++b)
      for (std::size_t e = 0; e + 1 < c[2].size(); ++e)
        worst = std::max(worst,
                         ps.box(c[0][a], c[0][a + 1], c[1][b], c[1][b + 1], c[2][e], c[2][e + 1]));
  return worst;
}

bool feasible(int n, int p, int minCells, int gran) {
  // p blocks of at least minCells cells, cuts on multiples of gran (the last block ends at n).
  const int minBlock = ((minCells + gran - 1) / gran) * gran;
  return static_cast<long long>(p - 1) * minBlock + minCells <= n;
}

/// Equal shares of the marginal cost along one axis, snapped to the granularity, then repaired
/// so every block keeps minCells cells.
std::vector<int> multisection(const std::vector<double>& marginal, int p, int minCells, int gran) {
  const int n = static_cast<int>(marginal.size());
  std::vector<double> prefix(static_cast<std::size_t>(n) + 1, 0.0);
  for (int i = 0; i < n; ++i)
    prefix[static_cast<std::size_t>(i) + 1] =
        prefix[static_cast<std::size_t>(i)] + marginal[static_cast<std::size_t>(i)];
  std::vector<int> cuts(static_cast<std::size_t>(p) + 1, 0);
  cuts.back() = n;
  for (int c = 1; c < p; ++c) {
    const double target = prefix.back() * c / p;
    int best = 0;
    double bestErr = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= n; i += gran) {
      const double err = std::abs(prefix[static_cast<std::size_t>(i)] - target);
      if (err < bestErr) bestErr = err, best = i;
    }
    cuts[static_cast<std::size_t>(c)] = best;
  }
  // Repair: forward pass enforces the minimum from the left, backward pass from the right.
  const int minBlock = ((minCells + gran - 1) / gran) * gran;
  for (int c = 1; c < p; ++c)
    cuts[static_cast<std::size_t>(c)] = std::max(cuts[static_cast<std::size_t>(c)],
                                                 cuts[static_cast<std::size_t>(c) - 1] + minBlock);
  for (int c = p - 1; c >= 1; --c) {
    int limit = cuts[static_cast<std::size_t>(c) + 1] - (c == p - 1 ? minCells : minBlock);
    limit -= limit % gran;
    cuts[static_cast<std::size_t>(c)] = std::min(cuts[static_cast<std::size_t>(c)], limit);
  }
  return cuts;
}

void refine(const PrefixSum& ps, std::array<std::vector<int>, 3>& cuts, int minCells, int gran) {
  double best = maxBlock(ps, cuts);
  for (int pass = 0; pass < 20; ++pass) {
    bool improved = false;
    for (int d = 0; d < 3; ++d) {
      auto& c = cuts[d];
      for (std::size_t i = 1; i + 1 < c.size(); ++i) {
        for (int step : {-gran, gran}) {
          const int moved = c[i] + step;
          if (moved - c[i - 1] < minCells || c[i + 1] - moved < minCells) continue;
          const int old = c[i];
          c[i] = moved;
          const double v = maxBlock(ps, cuts);
          if (v < best - 1e-12 * std::abs(best)) {
            best = v;
            improved = true;
          } else {
            c[i] = old;
          }
        }
      }
    }
    if (!improved) break;
  }
}

}  // namespace

std::vector<double> cellCosts(const Decomposition& dec, std::span<const double> x,
                              std::span<const double> y, std::span<const double> z,
                              const CostModel& model) {
  const auto& g = dec.grid();
  std::vector<double> cost(static_cast<std::size_t>(g.cellCount()), 0.0);
  for (std::size_t p = 0; p < x.size(); ++p) {
    const auto c = dec.cellOfPoint({x[p], y[p], z[p]});
    cost[static_cast<std::size_t>(c[0] + g.cells[0] * (c[1] + g.cells[1] * c[2]))] +=
        model.perParticle;
  }
  dec.comm().sumInPlace(std::span<double>(cost));
  for (double& c : cost) c += model.perCell;
  return cost;
}

std::vector<double> cellCostsOnRoot(const Decomposition& dec, std::span<const double> x,
                                    std::span<const double> y, std::span<const double> z,
                                    const CostModel& model) {
  const auto& g = dec.grid();
  const Int3 lo = dec.lo(), n = dec.cells();
  // Block-local dense part (x fastest), then (global index, value) pairs for cells outside.
  std::vector<double> local(static_cast<std::size_t>(dec.ownedCellCount()), 0.0);
  std::vector<double> outside;  // pairs: index as double (exact below 2^53), value
  for (std::size_t p = 0; p < x.size(); ++p) {
    const auto c = dec.cellOfPoint({x[p], y[p], z[p]});
    bool in = true;
    for (int d = 0; d < 3; ++d) in = in && c[d] >= lo[d] && c[d] < lo[d] + n[d];
    if (in) {
      local[static_cast<std::size_t>(
          (c[0] - lo[0]) + n[0] * ((c[1] - lo[1]) + n[1] * (c[2] - lo[2])))] += model.perParticle;
    } else {
      outside.push_back(static_cast<double>(c[0] + g.cells[0] * (c[1] + g.cells[1] * c[2])));
      outside.push_back(model.perParticle);
    }
  }
  local.insert(local.end(), outside.begin(), outside.end());
  const Comm& comm = dec.comm();
  const int size = comm.size(), me = comm.rank();
  int mine = static_cast<int>(local.size());
  std::vector<int> counts(me == 0 ? static_cast<std::size_t>(size) : 0), displ;
  MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm.raw());
  std::vector<double> all;
  if (me == 0) {
    const int total = Comm::displacements(counts, displ);
    all.resize(static_cast<std::size_t>(total));
  }
  MPI_Gatherv(local.data(), mine, MPI_DOUBLE, all.data(), counts.data(), displ.data(), MPI_DOUBLE,
              0, comm.raw());
  std::vector<double> cost;
  if (me != 0) return cost;
  cost.assign(static_cast<std::size_t>(g.cellCount()), 0.0);
  for (int r = 0; r < size; ++r) {
    const Int3 rl = dec.loOf(r), rh = dec.hiOf(r);
    const Int3 rn{rh[0] - rl[0], rh[1] - rl[1], rh[2] - rl[2]};
    const double* v = all.data() + displ[static_cast<std::size_t>(r)];
    std::size_t q = 0;
    for (int k = 0; k < rn[2]; ++k)
      for (int j = 0; j < rn[1]; ++j)
        for (int i = 0; i < rn[0]; ++i, ++q)
          cost[static_cast<std::size_t>(
              (rl[0] + i) + g.cells[0] * ((rl[1] + j) + g.cells[1] * (rl[2] + k)))] += v[q];
    for (; q + 1 < static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]); q += 2)
      cost[static_cast<std::size_t>(v[q])] += v[q + 1];
  }
  for (double& c : cost) c += model.perCell;
  return cost;
}

void evaluateLayout(const GlobalGrid& grid, const std::vector<double>& cost, BalancedLayout& l) {
  const PrefixSum ps(grid, cost);
  l.maxBlockCost = maxBlock(ps, l.cuts);
  double total = ps.box(0, grid.cells[0], 0, grid.cells[1], 0, grid.cells[2]);
  l.avgBlockCost = total / (l.dims[0] * l.dims[1] * l.dims[2]);
}

BalancedLayout balanceBlocks(const GlobalGrid& grid, const std::vector<double>& cost, int ranks,
                             int minCells, int granularity, Int3 fixedDims) {
  const PrefixSum ps(grid, cost);
  std::array<std::vector<double>, 3> marginal;
  for (int d = 0; d < 3; ++d) marginal[d].assign(static_cast<std::size_t>(grid.cells[d]), 0.0);
  for (int k = 0; k < grid.cells[2]; ++k)
    for (int j = 0; j < grid.cells[1]; ++j)
      for (int i = 0; i < grid.cells[0]; ++i) {
        const double v =
            cost[static_cast<std::size_t>(i + grid.cells[0] * (j + grid.cells[1] * k))];
        marginal[0][static_cast<std::size_t>(i)] += v;
        marginal[1][static_cast<std::size_t>(j)] += v;
        marginal[2][static_cast<std::size_t>(k)] += v;
      }
  BalancedLayout best;
  best.maxBlockCost = std::numeric_limits<double>::infinity();
  for (int px = 1; px <= ranks; ++px) {
    if (ranks % px) continue;
    for (int py = 1; py <= ranks / px; ++py) {
      if ((ranks / px) % py) continue;
      const Int3 dims{px, py, ranks / px / py};
      bool ok = true;
      for (int d = 0; d < 3; ++d) {
        if (fixedDims[d] > 0 && fixedDims[d] != dims[d]) ok = false;
        if (!feasible(grid.cells[d], dims[d], std::min(minCells, grid.cells[d]), granularity))
          ok = false;
      }
      if (!ok) continue;
      BalancedLayout l;
      l.dims = dims;
      for (int d = 0; d < 3; ++d)
        l.cuts[d] =
            multisection(marginal[d], dims[d], std::min(minCells, grid.cells[d]), granularity);
      refine(ps, l.cuts, minCells, granularity);
      l.maxBlockCost = maxBlock(ps, l.cuts);
      if (l.maxBlockCost < best.maxBlockCost * (1 - 1e-12)) best = l;
    }
  }
  if (!std::isfinite(best.maxBlockCost))
    throw ConfigError("partition.strategy",
                      fmt::format("no process grid of {} ranks fits the grid with blocks of at "
                                  "least {} cells",
                                  ranks, minCells));
  evaluateLayout(grid, cost, best);
  return best;
}

}  // namespace coloc
