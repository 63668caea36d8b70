#include "coloc/partition/strategy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "coloc/core/error.hpp"

namespace coloc {

Int3 Blocks::lo(int rank) const {
  const Int3 c = coordsOf(rank);
  return {cuts[0][static_cast<std::size_t>(c[0])], cuts[1][static_cast<std::size_t>(c[1])],
          cuts[2][static_cast<std::size_t>(c[2])]};
}

Int3 Blocks::hi(int rank) const {
  const Int3 c = coordsOf(rank);
  return {cuts[0][static_cast<std::size_t>(c[0]) + 1], cuts[1][static_cast<std::size_t>(c[1]) + 1],
          cuts[2][static_cast<std::size_t>(c[2]) + 1]};
}

int Blocks::neighbour(const GlobalGrid& g, int rank, int d, int side) const {
  Int3 c = coordsOf(rank);
  c[d] += side > 0 ? 1 : -1;
  if (c[d] < 0 || c[d] >= dims[d]) {
    if (!g.periodic[d]) return -1;
    c[d] = (c[d] + dims[d]) % dims[d];
  }
  return rankOf(c);
}

int Blocks::blockAlong(int d, int cell) const {
  const auto& c = cuts[d];
  return static_cast<int>(std::upper_bound(c.begin(), c.end(), cell) - c.begin()) - 1;
}

Blocks blocksOf(const Decomposition& dec) {
  return {dec.dims(), dec.cuts()};
}

Blocks uniformBlocks(const StrategyInput& in) {
  Blocks b;
  b.dims = Decomposition::chooseDims(in.ranks, in.grid, in.dims, in.minCells);
  if (b.size() != in.ranks)
    throw ConfigError("partition.dims", "process grid " + std::to_string(b.dims[0]) + "x" +
                                            std::to_string(b.dims[1]) + "x" +
                                            std::to_string(b.dims[2]) + " does not match " +
                                            std::to_string(in.ranks) + " ranks");
  for (int d = 0; d < 3; ++d) {
    if (b.dims[d] > in.grid.cells[d])
      throw ConfigError("partition.dims", std::to_string(b.dims[d]) + " ranks along " + "xyz"[d] +
                                              " but only " + std::to_string(in.grid.cells[d]) +
                                              " cells: each block needs a cell");
    b.cuts[d] = Decomposition::evenCuts(in.grid.cells[d], b.dims[d]);
  }
  return b;
}

StrategyBlocks chooseBlocks(const std::string& strategy, const StrategyInput& in,
                            const std::vector<double>& cost, const std::vector<double>& count) {
  StrategyBlocks out;
  out.strategy = strategy;
  out.fluid = uniformBlocks(in);
  if (strategy == "uniform") return out;
  const auto& g = in.grid;
  const int gran = std::max(1, in.granularity);
  const int minCells = std::max(2, in.minCells);  // the balancer's thinnest block (ghosts)
  const int size = in.ranks;
  if (strategy == "independent") {
    BalancedLayout best;
    if (in.demDims == Int3{0, 0, 0}) {
      // The baseline keeps its physics apart: prefer a process grid other than the fluid's.
      best.maxBlockCost = std::numeric_limits<double>::infinity();
      for (int px = 1; px <= size; ++px)
        for (int py = 1; py <= size / px; ++py) {
          if (size % (px * py)) continue;
          const Int3 dims{px, py, size / (px * py)};
          if (dims == out.fluid.dims && size > 1) continue;
          try {
            const auto l = balanceBlocks(g, count, size, minCells, gran, dims);
            if (l.maxBlockCost < best.maxBlockCost) best = l;
          } catch (const ConfigError&) {
          }
        }
      if (!std::isfinite(best.maxBlockCost)) best = balanceBlocks(g, count, size, minCells, gran);
    } else {
      best = balanceBlocks(g, count, size, minCells, gran, in.demDims);
    }
    out.particles = Blocks{best.dims, best.cuts};
    return out;
  }
  if (strategy != "balanced")
    throw ConfigError("partition.strategy", "unknown strategy '" + strategy + "'");
  const BalancedLayout best = balanceBlocks(g, cost, size, minCells, gran, in.dims);
  BalancedLayout uni;
  uni.dims = out.fluid.dims;
  uni.cuts = out.fluid.cuts;
  evaluateLayout(g, cost, uni);
  out.fluid = Blocks{best.dims, best.cuts};
  out.modelledImbalance = best.imbalance();
  out.uniformImbalance = uni.imbalance();
  return out;
}

TiledLayout tiledStrategy(const StrategyInput& in, const std::vector<double>& cost,
                          double surfaceCost) {
  TiledOptions opt;
  opt.minCells = std::max(2, in.minCells);
  opt.granularity = std::max(1, in.granularity);
  opt.surfaceCost = surfaceCost;
  opt.ghost = 2;
  TiledLayout best = tiledBoxes(in.grid, cost, in.ranks, opt);
  // A separable layout is a tiled layout too: the balanced strategy's blocks are kept where they
  // are more balanced, or as balanced (0.1 %) with fewer halo cells.
  try {
    const BalancedLayout sep =
        balanceBlocks(in.grid, cost, in.ranks, opt.minCells, opt.granularity, in.dims);
    const Blocks b{sep.dims, sep.cuts};
    TiledLayout t;
    t.layout.grid = in.grid;
    for (int r = 0; r < in.ranks; ++r) t.layout.box.push_back({b.lo(r), b.hi(r)});
    evaluateBoxes(cost, opt, t);
    // as tiledBoxes chooses among its own layouts: cheapest largest box, within 0.1 % fewest
    // halo cells
    const auto halo = [&](const TiledLayout& x) {
      long long h = 0;
      for (const auto& b : x.layout.box) h += haloCells(in.grid, b, opt.ghost);
      return h;
    };
    if (t.maxCost < best.maxCost * (1 - 1e-3) ||
        (t.maxCost <= best.maxCost * (1 + 1e-3) && halo(t) < halo(best)))
      best = std::move(t);
  } catch (const ConfigError&) {
    // no process grid fits: the bisection's boxes stand
  }
  return best;
}

}  // namespace coloc
