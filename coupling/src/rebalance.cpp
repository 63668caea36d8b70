#include "coloc/coupling/rebalance.hpp"

#include <algorithm>
#include <cstdio>

#include "coloc/partition/balance.hpp"

namespace coloc::coupling {

bool rebalanceDue(const Config& cfg, long long steps) {
  const long long every = cfg.integer("partition.rebalance_interval");
  return every > 0 && steps > 0 && steps % every == 0 &&
         cfg.string("partition.strategy") == "balanced";
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
  if (!dem || sim.independent()) return plan;

  const auto& p = dem->particles();
  const std::size_t m = p.nOwned;
  const auto cost = cellCosts(dec, std::span<const double>(p.x[0].data(), m),
                              std::span<const double>(p.x[1].data(), m),
                              std::span<const double>(p.x[2].data(), m), plan.model);
  BalancedLayout current;
  current.dims = dec.dims();
  current.cuts = dec.cuts();
  evaluateLayout(g, cost, current);
  const int gran = static_cast<int>(std::max<long long>(1, cfg.integer("particles.bin_cells")));
  const auto fixed = cfg.intVec3("partition.dims");
  const BalancedLayout best =
      balanceBlocks(g, cost, comm.size(), /*minCells=*/2, gran,
                    Int3{static_cast<int>(fixed[0]), static_cast<int>(fixed[1]),
                         static_cast<int>(fixed[2])});
  plan.currentImbalance = current.imbalance();
  plan.newImbalance = best.imbalance();
  plan.gain = best.maxBlockCost > 0 ? current.maxBlockCost / best.maxBlockCost : 1.0;
  if (plan.gain < cfg.number("partition.rebalance_threshold")) return plan;
  BalancedLayout even;  // what uniform blocks would give now, for the report
  {
    const Decomposition u = Decomposition::uniform(
        comm, g, Int3{static_cast<int>(fixed[0]), static_cast<int>(fixed[1]),
                      static_cast<int>(fixed[2])});
    even.dims = u.dims();
    even.cuts = u.cuts();
    evaluateLayout(g, cost, even);
  }
  Layouts L{Decomposition::fromCuts(comm, g, best.cuts), std::nullopt, "balanced", plan.model,
            best.imbalance(), even.imbalance()};
  plan.layouts = std::move(L);
  return plan;
}

std::unique_ptr<Simulation> applyRebalance(std::unique_ptr<Simulation> sim, const Config& cfg,
                                           Layouts layouts, const std::string& scratch) {
  const double t0 = MPI_Wtime(), c0 = threadCpuSeconds();
  Timers timers = sim->timers();
  const auto start = sim->runStart();
  const Comm& comm = sim->decomposition().comm();
  sim->writeCheckpoint(scratch);
  const bool root = comm.isRoot();
  sim.reset();
  auto next = std::make_unique<Simulation>(cfg, std::move(layouts), scratch);
  next->decomposition().comm().barrier();
  if (root) std::remove(scratch.c_str());
  timers.add(Phase::Rebalance, MPI_Wtime() - t0, threadCpuSeconds() - c0);
  next->resumeRun(start, timers);
  return next;
}

}  // namespace coloc::coupling
