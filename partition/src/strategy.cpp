#include "coloc/partition/strategy.hpp"

#include <fmt/format.h>

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
    throw ConfigError("partition.dims", fmt::format("process grid {}x{}x{} does not match {} ranks",
                                                    b.dims[0], b.dims[1], b.dims[2], in.ranks));
  for (int d = 0; d < 3; ++d) {
    if (b.dims[d] > in.grid.cells[d])
      throw ConfigError("partition.dims",
                        fmt::format("{} ranks along {} but only {} cells: each block needs a cell",
                                    b.dims[d], "xyz"[d], in.grid.cells[d]));
    b.cuts[d] = Decomposition::evenCuts(in.grid.cells[d], b.dims[d]);
  }
  return b;
}

StrategyLayout layoutOf(const Decomposition& dec) {
  StrategyLayout l;
  l.fluid = l.particles = boxLayoutOf(dec);
  if (!dec.isTiled()) l.fluidBlocks = blocksOf(dec);
  return l;
}

BoxLayout boxesOf(const GlobalGrid& g, const Blocks& b) {
  BoxLayout l;
  l.grid = g;
  for (int r = 0; r < b.size(); ++r) l.box.push_back({b.lo(r), b.hi(r)});
  return l;
}

StrategyLayout blocksLayout(const GlobalGrid& g, const Blocks& fluid,
                            const std::optional<Blocks>& particles) {
  StrategyLayout l;
  l.fluid = boxesOf(g, fluid);
  l.particles = particles ? boxesOf(g, *particles) : l.fluid;
  l.fluidBlocks = fluid;
  l.particleBlocks = particles;
  return l;
}

namespace {

/// A process grid's blocks measured under `cost`: the balancer's largest and mean block cost.
BalancedLayout measured(const GlobalGrid& g, const std::vector<double>& cost, const Blocks& b) {
  BalancedLayout l;
  l.dims = b.dims;
  l.cuts = b.cuts;
  evaluateLayout(g, cost, l);
  return l;
}

class Uniform final : public PartitionStrategy {
 public:
  std::string_view name() const override { return "uniform"; }
  StrategyLayout layout(const StrategyInput& in, const CellWork&) const override {
    return blocksLayout(in.grid, uniformBlocks(in));
  }
};

/// One grid for both physics, its cuts placed on the modelled cost (balanceBlocks).
class Balanced final : public PartitionStrategy {
 public:
  std::string_view name() const override { return "balanced"; }
  bool balancesCost() const override { return true; }
  StrategyLayout layout(const StrategyInput& in, const CellWork& w) const override {
    const Blocks uniform = uniformBlocks(in);
    const BalancedLayout best = balanceBlocks(in.grid, w.cost, in.ranks, std::max(2, in.minCells),
                                              std::max(1, in.granularity), in.dims);
    StrategyLayout l = blocksLayout(in.grid, Blocks{best.dims, best.cuts});
    l.modelledImbalance = best.imbalance();
    l.maxCost = best.maxBlockCost;
    l.meanCost = best.avgBlockCost;
    l.uniformImbalance = measured(in.grid, w.cost, uniform).imbalance();
    return l;
  }
  StrategyLayout evaluate(StrategyLayout current, const StrategyInput& in,
                          const CellWork& w) const override {
    if (!current.fluidBlocks) throw Error("balanced: the layout to evaluate has no process grid");
    const BalancedLayout now = measured(in.grid, w.cost, *current.fluidBlocks);
    current.modelledImbalance = now.imbalance();
    current.maxCost = now.maxBlockCost;
    current.meanCost = now.avgBlockCost;
    current.uniformImbalance = measured(in.grid, w.cost, uniformBlocks(in)).imbalance();
    return current;
  }
};

/// The baseline: the fluid on the uniform blocks, the DEM on blocks of its own balanced by
/// particle count, on a process grid other than the fluid's where one fits.
class Independent final : public PartitionStrategy {
 public:
  std::string_view name() const override { return "independent"; }
  bool ownParticleBlocks() const override { return true; }
  StrategyLayout layout(const StrategyInput& in, const CellWork& w) const override {
    const Blocks fluid = uniformBlocks(in);
    const auto& g = in.grid;
    const int gran = std::max(1, in.granularity);
    const int minCells = std::max(2, in.minCells);  // the balancer's thinnest block (ghosts)
    const int size = in.ranks;
    BalancedLayout best;
    if (in.demDims == Int3{0, 0, 0}) {
      best.maxBlockCost = std::numeric_limits<double>::infinity();
      for (int px = 1; px <= size; ++px)
        for (int py = 1; py <= size / px; ++py) {
          if (size % (px * py)) continue;
          const Int3 dims{px, py, size / (px * py)};
          if (dims == fluid.dims && size > 1) continue;
          try {
            const auto l = balanceBlocks(g, w.count, size, minCells, gran, dims);
            if (l.maxBlockCost < best.maxBlockCost) best = l;
          } catch (const ConfigError&) {
          }
        }
      if (!std::isfinite(best.maxBlockCost)) best = balanceBlocks(g, w.count, size, minCells, gran);
    } else {
      best = balanceBlocks(g, w.count, size, minCells, gran, in.demDims);
    }
    return blocksLayout(g, fluid, Blocks{best.dims, best.cuts});
  }
};

/// One box per rank by recursive bisection of the modelled cost (tiledStrategy): no process grid.
class Tiled final : public PartitionStrategy {
 public:
  std::string_view name() const override { return "tiled"; }
  bool balancesCost() const override { return true; }
  bool gridLayout() const override { return false; }
  bool plannedByDefault() const override { return false; }
  StrategyLayout startLayout(const StrategyInput& in, double haloCell) const override {
    const std::vector<double> cells(static_cast<std::size_t>(in.grid.cellCount()), 1.0);
    return layout(in, CellWork{cells, {}, haloCell});
  }
  StrategyLayout layout(const StrategyInput& in, const CellWork& w) const override {
    const TiledLayout t = tiledStrategy(in, w.cost, w.haloCell);
    StrategyLayout l;
    l.fluid = l.particles = t.layout;
    l.modelledImbalance = t.imbalance();
    l.maxCost = t.maxCost;
    l.meanCost = t.avgCost;
    l.uniformImbalance = uniformImbalance(in, w);
    return l;
  }
  StrategyLayout evaluate(StrategyLayout current, const StrategyInput& in,
                          const CellWork& w) const override {
    TiledLayout now;
    now.layout = current.fluid;
    TiledOptions opt;
    opt.surfaceCost = w.haloCell;
    evaluateBoxes(w.cost, opt, now);
    current.modelledImbalance = now.imbalance();
    current.maxCost = now.maxCost;
    current.meanCost = now.avgCost;
    current.uniformImbalance = uniformImbalance(in, w);
    return current;
  }

 private:
  /// The uniform blocks' imbalance under the same cost; NaN (null in reports) where no process
  /// grid fits the rank count.
  static double uniformImbalance(const StrategyInput& in, const CellWork& w) {
    try {
      return measured(in.grid, w.cost, uniformBlocks(in)).imbalance();
    } catch (const ConfigError&) {
      return std::numeric_limits<double>::quiet_NaN();
    }
  }
};

const Uniform kUniform;
const Balanced kBalanced;
const Independent kIndependent;
const Tiled kTiled;
const PartitionStrategy* const kAll[] = {&kUniform, &kBalanced, &kIndependent, &kTiled};

}  // namespace

StrategyLayout PartitionStrategy::startLayout(const StrategyInput& in, double /*haloCell*/) const {
  return blocksLayout(in.grid, uniformBlocks(in));
}

StrategyLayout PartitionStrategy::evaluate(StrategyLayout, const StrategyInput&,
                                           const CellWork&) const {
  throw Error("partition.strategy " + std::string(name()) +
              " does not balance the modelled cost: nothing to evaluate");
}

StrategyLayout PartitionStrategy::layoutFor(RunMode mode, const StrategyInput& in,
                                            const CellWork& work) const {
  return mode == RunMode::FluidOnly ? startLayout(in, work.haloCell) : layout(in, work);
}

std::span<const PartitionStrategy* const> PartitionStrategy::all() {
  return kAll;
}

std::vector<std::string> PartitionStrategy::names() {
  std::vector<std::string> out;
  for (const PartitionStrategy* s : kAll) out.emplace_back(s->name());
  return out;
}

const PartitionStrategy& PartitionStrategy::named(std::string_view name, const std::string& key) {
  std::string list;
  for (const PartitionStrategy* s : kAll) {
    if (s->name() == name) return *s;
    list += (list.empty() ? "" : ", ") + std::string(s->name());
  }
  throw ConfigError(key, "unknown strategy '" + std::string(name) + "' (" + list + ")");
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
    t.layout = boxesOf(in.grid, b);
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
