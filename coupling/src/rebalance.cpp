#include "coloc/coupling/rebalance.hpp"

#include <algorithm>
#include <cstdio>

#include "coloc/core/error.hpp"
#include "coloc/coupling/layouts.hpp"
#include "coloc/partition/balance.hpp"
#include "coloc/partition/strategy.hpp"

namespace coloc::coupling {

long long rebalanceInterval(const Config& cfg) {
  const std::string s = cfg.string("partition.strategy");
  return s == "balanced" || s == "tiled" ? cfg.integer("partition.rebalance_interval") : 0;
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
  if (dec.isTiled()) {  // the bisection anew on the same cost, the boxes moved when it pays
    std::array<double, 2> verdict{1.0, 1.0};
    Layouts L = tiledLayoutsOnRoot(comm, cfg, cost, plan.model, &dec, &verdict);
    plan.currentImbalance = verdict[0];
    plan.newImbalance = L.modelledImbalance;
    plan.gain = verdict[1];
    if (plan.gain >= cfg.number("partition.rebalance_threshold")) plan.layouts = std::move(L);
    return plan;
  }
  const int gran = static_cast<int>(std::max<long long>(1, cfg.integer("particles.bin_cells")));
  const auto fixed = cfg.intVec3("partition.dims");
  const Int3 fixedDims{static_cast<int>(fixed[0]), static_cast<int>(fixed[1]),
                       static_cast<int>(fixed[2])};
  double verdict[3] = {1.0, 1.0, 1.0};  // current imbalance, new imbalance, gain
  double evenImbalance = 1.0;
  std::vector<int> packed;  // dims, then the cuts of the new blocks
  std::string err;
  if (comm.isRoot()) {
    try {
      BalancedLayout current;
      current.dims = dec.dims();
      current.cuts = dec.cuts();
      evaluateLayout(g, cost, current);
      const BalancedLayout best =
          balanceBlocks(g, cost, comm.size(), /*minCells=*/2, gran, fixedDims);
      verdict[0] = current.imbalance();
      verdict[1] = best.imbalance();
      verdict[2] = best.maxBlockCost > 0 ? current.maxBlockCost / best.maxBlockCost : 1.0;
      BalancedLayout even;  // what uniform blocks would give now, for the report
      StrategyInput in = strategyInput(cfg, comm.size());
      const Blocks u = uniformBlocks(in);
      even.dims = u.dims;
      even.cuts = u.cuts;
      evaluateLayout(g, cost, even);
      evenImbalance = even.imbalance();
      for (int d = 0; d < 3; ++d) packed.push_back(best.dims[d]);
      for (int d = 0; d < 3; ++d)
        packed.insert(packed.end(), best.cuts[d].begin(), best.cuts[d].end());
    } catch (const Error& e) {
      err = e.what();
    }
  }
  err = comm.broadcast(err);
  if (!err.empty()) throw Error(err);
  comm.broadcast(std::span<double>(verdict, 3));
  comm.broadcast(std::span<double>(&evenImbalance, 1));
  plan.currentImbalance = verdict[0];
  plan.newImbalance = verdict[1];
  plan.gain = verdict[2];
  if (plan.gain < cfg.number("partition.rebalance_threshold")) return plan;
  int len = static_cast<int>(packed.size());
  comm.broadcast(std::span<int>(&len, 1));
  packed.resize(static_cast<std::size_t>(len));
  comm.broadcast(std::span<int>(packed));
  std::array<std::vector<int>, 3> cuts;
  std::size_t q = 3;
  for (int d = 0; d < 3; ++d) {
    cuts[d].assign(
        packed.begin() + static_cast<std::ptrdiff_t>(q),
        packed.begin() + static_cast<std::ptrdiff_t>(q) + packed[static_cast<std::size_t>(d)] + 1);
    q += static_cast<std::size_t>(packed[static_cast<std::size_t>(d)]) + 1;
  }
  Layouts L{Decomposition::fromCuts(comm, g, std::move(cuts)),
            std::nullopt,
            "balanced",
            plan.model,
            verdict[1],
            evenImbalance};
  plan.layouts = std::move(L);
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
