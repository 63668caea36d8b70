// The strategy choice of a run (Simulation::chooseLayouts): the PartitionStrategy
// partition.strategy names (partition/strategy.hpp), its blocks from the cost probe (layouts.hpp),
// with the cost weights measured by a short run when partition.calibrate_steps asks for it.
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

}  // namespace

Layouts chooseLayouts(const Comm& world, const Config& cfg) {
  const PartitionStrategy& strategy = PartitionStrategy::named(cfg.string("partition.strategy"));
  if (cfg.integer("partition.rebalance_interval") > 0 && !strategy.balancesCost())
    throw ConfigError("partition.rebalance_interval",
                      "re-balancing moves the cuts of the balanced or tiled strategies: set "
                      "partition.strategy to balanced or tiled (it is '" +
                          std::string(strategy.name()) + "')");
  // The layout before any cost is known (the same on every rank, no communication): a fluid-only
  // run keeps it; the calibration runs and the cost probe counts the particles on it.
  const StrategyInput in = strategyInput(cfg, world.size());
  const double haloCell = cfg.number("partition.cost.halo_cell");
  // (Tiled boxes come from a bisection over every global cell: on rank 0 alone.)
  const auto first = [&] { return strategy.startLayout(in, haloCell); };
  Layouts start = runLayouts(world, strategy,
                             strategy.gridLayout() ? first() : layoutOnRoot(world, in.grid, first),
                             CostModel{});
  if (runMode(cfg) == RunMode::FluidOnly) return start;
  if (!strategy.balancesCost() && !strategy.ownParticleBlocks()) return start;  // uniform
  CostModel model{cfg.number("partition.cost.cell"), cfg.number("partition.cost.particle")};
  if (strategy.balancesCost() && cfg.integer("partition.calibrate_steps") > 0)
    model = calibrate(cfg, start.fluid, cfg.integer("partition.calibrate_steps"));
  // Where the particles start (the cost probe: the case's generator, no solver), counted per
  // cell on rank 0 only (cellCostsOnRoot), which chooses the blocks and sends them to every
  // rank: no rank but the root holds anything of the global cell count. Particle blocks of
  // their own are balanced by count.
  const std::vector<double> cost = probeCellCostsOnRoot(
      cfg, start.fluid, strategy.ownParticleBlocks() ? CostModel{0.0, 1.0} : model);
  const std::vector<double> none;
  const StrategyLayout chosen = layoutOnRoot(world, in.grid, [&] {
    return strategy.layout(in, strategy.ownParticleBlocks() ? CellWork{none, cost, haloCell}
                                                            : CellWork{cost, none, haloCell});
  });
  if (strategy.ownParticleBlocks()) model = CostModel{};
  return runLayouts(world, strategy, chosen, model);
}

}  // namespace coloc::coupling
