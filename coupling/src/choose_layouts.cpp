// The strategy choice of a run (Simulation::chooseLayouts): partition.strategy's blocks from the
// cost probe (layouts.hpp), with the cost weights measured by a short run when
// partition.calibrate_steps asks for it.
#include <optional>
#include <string>
#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/coupling/layouts.hpp"
#include "coloc/coupling/simulation.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

namespace {

/// Cost weights measured on the uniform blocks (tiled: boxes of equal cells): busy seconds of the
/// fluid phases per cell-step and of the particle and coupling phases per particle-step (summed
/// over ranks).
CostModel calibrate(const Config& cfg, const Decomposition& uniform, long long steps) {
  Layouts probe{uniform, std::nullopt, "uniform", CostModel{}, 1.0, 1.0};
  Simulation sim(cfg, probe);
  for (long long s = 0; s < steps; ++s) sim.step();
  const Comm& comm = uniform.comm();
  double fluid = 0, particles = 0;
  for (std::size_t i = 0; i < kPhases.size(); ++i) {
    const double b = sim.timers().busySeconds(static_cast<Phase>(i));
    if (kPhases[i].category == Category::Fluid) fluid += b;
    if (kPhases[i].category == Category::Particles || kPhases[i].category == Category::Coupling)
      particles += b;
  }
  fluid = comm.sum(fluid);
  particles = comm.sum(particles);
  const double cells = static_cast<double>(uniform.grid().cellCount());
  const double n = sim.particles() ? static_cast<double>(sim.particles()->globalCount()) : 0.0;
  CostModel m;
  m.perCell = fluid / (cells * static_cast<double>(steps));
  m.perParticle = n > 0 ? particles / (n * static_cast<double>(steps)) : 0.0;
  if (!(m.perCell > 0)) m.perCell = 1e-12;
  return m;
}

/// The tiled strategy, for any rank count (no process grid is needed on the way): boxes of
/// equal cell counts first, the layout of a fluid-only run and where the calibration runs and
/// the cost probe counts the particles; then the boxes of the modelled cost.
Layouts chooseTiled(const Comm& world, const Config& cfg) {
  const GlobalGrid grid = gridFromConfig(cfg);
  std::vector<double> cells;
  if (world.isRoot()) cells.assign(static_cast<std::size_t>(grid.cellCount()), 1.0);
  Layouts equal = tiledLayoutsOnRoot(world, cfg, cells, CostModel{1.0, 0.0});
  if (runMode(cfg) == RunMode::FluidOnly) return equal;
  CostModel model{cfg.number("partition.cost.cell"), cfg.number("partition.cost.particle")};
  if (cfg.integer("partition.calibrate_steps") > 0)
    model = calibrate(cfg, equal.fluid, cfg.integer("partition.calibrate_steps"));
  const std::vector<double> cost = probeCellCostsOnRoot(cfg, equal.fluid, model);
  return tiledLayoutsOnRoot(world, cfg, cost, model);
}

}  // namespace

Layouts chooseLayouts(const Comm& world, const Config& cfg) {
  const std::string strategy = cfg.string("partition.strategy");
  if (cfg.integer("partition.rebalance_interval") > 0 && strategy != "balanced" &&
      strategy != "tiled")
    throw ConfigError("partition.rebalance_interval",
                      "re-balancing moves the cuts of the balanced or tiled strategies: set "
                      "partition.strategy to balanced or tiled (it is '" +
                          strategy + "')");
  if (strategy == "tiled") return chooseTiled(world, cfg);
  const Decomposition uniform = decompositionFromConfig(world, cfg);
  Layouts L{uniform, std::nullopt, strategy, CostModel{}, 1.0, 1.0};
  if (strategy == "uniform" || runMode(cfg) == RunMode::FluidOnly) return L;
  const bool independent = strategy == "independent";
  CostModel model{cfg.number("partition.cost.cell"), cfg.number("partition.cost.particle")};
  if (!independent && cfg.integer("partition.calibrate_steps") > 0)
    model = calibrate(cfg, uniform, cfg.integer("partition.calibrate_steps"));
  // Where the particles start (the cost probe: the case's generator, no solver), counted per
  // cell on rank 0 only (cellCostsOnRoot), which chooses the blocks and sends them to every
  // rank: no rank but the root holds anything of the global cell count.
  // independent: the DEM's blocks are balanced by particle count.
  const std::vector<double> cost =
      probeCellCostsOnRoot(cfg, uniform, independent ? CostModel{0.0, 1.0} : model);
  const StrategyInput in = strategyInput(cfg, world.size());
  const StrategyBlocks b = chooseBlocksOnRoot(world, strategy, in, cost, independent);
  if (independent) {
    L.particles = Decomposition::fromCuts(world, in.grid, b.particles->cuts);
    return L;
  }
  L.fluid = Decomposition::fromCuts(world, in.grid, b.fluid.cuts);
  L.model = model;
  L.modelledImbalance = b.modelledImbalance;
  L.uniformImbalance = b.uniformImbalance;
  return L;
}

}  // namespace coloc::coupling
