#include "coloc/coupling/rebalance.hpp"

#include <algorithm>
#include <cstdio>

#include "coloc/core/error.hpp"
#include "coloc/coupling/layouts.hpp"
#include "coloc/partition/balance.hpp"
#include "coloc/partition/strategy.hpp"

namespace coloc::coupling {

long long rebalanceInterval(const Config& cfg) {
  return PartitionStrategy::named(cfg.string("partition.strategy")).balancesCost()
             ? cfg.integer("partition.rebalance_interval")
             : 0;
}

bool rebalanceDue(const Config& cfg, long long steps) {
  return rebalanceDue(rebalanceInterval(cfg), steps);
}

RebalancePlan planRebalance(Simulation& sim, const Config& cfg) {
  RebalancePlan plan;
  const Decomposition& dec = sim.decomposition();
  const Comm& comm = dec.comm();
  const GlobalGrid& g = dec.grid();
  // Weights from the run's own timers: seconds per cell and per particle over the steps so far.
  double busy[2] = {0, 0};
  for (std::size_t i = 0; i < kPhases.size(); ++i) {
    if (!kPhases[i].compute) continue;
    const double b = sim.timers().busySeconds(static_cast<Phase>(i));
    if (kPhases[i].category == Category::Fluid) busy[0] += b;
    if (kPhases[i].category == Category::Particles || kPhases[i].category == Category::Coupling)
      busy[1] += b;
  }
  comm.sumInPlace(std::span<double>(busy, 2));
  const auto* dem = sim.particles();
  const double n = dem ? static_cast<double>(dem->globalCount()) : 0.0;
  plan.model.perCell = std::max(busy[0] / static_cast<double>(g.cellCount()), 1e-15);
  plan.model.perParticle = n > 0 ? busy[1] / n : 0.0;
  if (cfg.string("partition.rebalance_weights") == "case") {  // reproducible cuts
    plan.model.perCell = std::max(cfg.number("partition.cost.cell"), 1e-15);
    plan.model.perParticle = cfg.number("partition.cost.particle");
  }
  if (!dem || sim.independent()) return plan;

  const auto& p = dem->particles();
  const std::size_t m = p.nOwned;
  // Rank 0 alone gathers the cost of every cell (cellCostsOnRoot), evaluates the blocks and
  // sends the verdict and the new cuts to every rank.
  const auto cost = cellCostsOnRoot(dec, std::span<const double>(p.x[0].data(), m),
                                    std::span<const double>(p.x[1].data(), m),
                                    std::span<const double>(p.x[2].data(), m), plan.model);
  // The strategy's own layout anew on that cost, and the blocks in use measured as it measures
  // its own: the layout moves when its largest block cost drops by the threshold.
  const PartitionStrategy& strategy = PartitionStrategy::named(cfg.string("partition.strategy"));
  const StrategyInput in = strategyInput(cfg, comm.size());
  const double haloCell = cfg.number("partition.cost.halo_cell");
  double current[2] = {1.0, 0.0};  // the blocks in use: imbalance, largest block cost
  const StrategyLayout next = layoutOnRoot(comm, g, [&] {
    const std::vector<double> none;
    const CellWork work{cost, none, haloCell};
    const StrategyLayout now = strategy.evaluate(layoutOf(dec), in, work);
    current[0] = now.modelledImbalance;
    current[1] = now.maxCost;
    return strategy.layout(in, work);
  });
  comm.broadcast(std::span<double>(current, 2));
  plan.currentImbalance = current[0];
  plan.newImbalance = next.modelledImbalance;
  plan.gain = next.maxCost > 0 ? current[1] / next.maxCost : 1.0;
  if (plan.gain >= cfg.number("partition.rebalance_threshold"))
    plan.layouts = runLayouts(comm, strategy, next, plan.model);
  return plan;
}

std::unique_ptr<Simulation> applyRebalance(std::unique_ptr<Simulation> sim, const Config& cfg,
                                           Layouts layouts) {
  const double t0 = MPI_Wtime(), c0 = threadCpuSeconds();
  Timers timers = sim->timers();
  const auto start = sim->runStart();
  auto next = std::make_unique<Simulation>(cfg, std::move(layouts), *sim);
  sim.reset();
  timers.add(Phase::Rebalance, MPI_Wtime() - t0, threadCpuSeconds() - c0);
  next->resumeRun(start, timers);
  return next;
}

std::unique_ptr<Simulation> applyRebalance(std::unique_ptr<Simulation> sim, const Config& cfg,
                                           Layouts layouts, const std::string& /*scratch*/) {
  return applyRebalance(std::move(sim), cfg, std::move(layouts));
}

std::unique_ptr<Simulation> applyRebalanceThroughFile(std::unique_ptr<Simulation> sim,
                                                      const Config& cfg, Layouts layouts,
                                                      const std::string& scratch) {
  const double t0 = MPI_Wtime(), c0 = threadCpuSeconds();
  Timers timers = sim->timers();
  const auto start = sim->runStart();
  const Comm& comm = sim->decomposition().comm();
  sim->writeCheckpoint(scratch);
  const bool root = comm.isRoot();
  sim.reset();
  auto next = std::make_unique<Simulation>(cfg, std::move(layouts), scratch);
  if (root) std::remove(scratch.c_str());  // every rank closed it in the constructor
  next->decomposition().comm().barrier();
  timers.add(Phase::Rebalance, MPI_Wtime() - t0, threadCpuSeconds() - c0);
  next->resumeRun(start, timers);
  return next;
}

}  // namespace coloc::coupling
