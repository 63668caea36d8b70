// coloc/coupling/layouts.hpp — the blocks a run uses (Layouts), the case's constraints on them
// and the cost probe: where the case's particles start, without a solver.
//
// The strategies themselves are in partition/strategy.hpp (class PartitionStrategy, for any rank
// count); here they meet a live communicator (layoutOnRoot, runLayouts) and the case's particles
// (probeParticles: dem::caseParticles, the run's own generator, no DemSolver). The run's
// Simulation::chooseLayouts and `coloc check` use the same probe.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/partition/balance.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/strategy.hpp"

namespace coloc::coupling {

/// The blocks of the two physics chosen by partition.strategy.
struct Layouts {
  Decomposition fluid;
  std::optional<Decomposition> particles;  // set only in independent mode
  std::string strategy = "uniform";
  CostModel model;                 // balanced: the weights used
  double modelledImbalance = 1.0;  // balanced: max/avg modelled block cost
  double uniformImbalance = 1.0;   // balanced: the same for the uniform blocks
};

/// The case's constraints on the blocks of `ranks` ranks (partition.dims, partition.dem_dims,
/// run.mode, particles.bin_cells): what a PartitionStrategy (partition/strategy.hpp) takes.
StrategyInput strategyInput(const Config& cfg, int ranks);
/// The strategy of a run's layouts (PartitionStrategy::named(L.strategy)).
const PartitionStrategy& strategyOf(const Layouts& L);

/// `choose` called on rank 0 alone, which alone holds the cells' work (cellCostsOnRoot), and the
/// layout it returns on every rank (the cuts of a process grid, else 6 ints a box; the
/// imbalances and costs). Collective; an error of the root is raised on every rank.
StrategyLayout layoutOnRoot(const Comm& comm, const GlobalGrid& grid,
                            const std::function<StrategyLayout()>& choose);

/// A run's Layouts on `layout` (the same on every rank): Decompositions of `comm`'s ranks, a
/// process grid's (Decomposition::fromCuts) or tiled boxes (fromBoxes). Collective.
Layouts runLayouts(const Comm& comm, const PartitionStrategy& strategy,
                   const StrategyLayout& layout, const CostModel& model);

/// The case's initial particles as the run creates them, without a solver: the centres that lie
/// in this rank's block of `dec` (each particle on exactly one rank), and over all of them
/// (every rank, no communication) their count and radius range.
struct ParticleProbe {
  std::array<std::vector<double>, 3> x;
  long long total = 0;
  double rMin = 0, rMax = 0;
};
ParticleProbe probeParticles(const Config& cfg, const Decomposition& dec);

/// The modelled cost of every global cell on rank 0 (empty elsewhere): cellCostsOnRoot of the
/// probe's particles under `model`. Collective.
std::vector<double> probeCellCostsOnRoot(const Config& cfg, const Decomposition& dec,
                                         const CostModel& model);

/// The blocks partition.strategy asks for on `world` (coupling/src/choose_layouts.cpp): uniform
/// blocks, or the balanced / independent cuts from the cost probe, the weights measured first
/// by a short run on the uniform blocks when partition.calibrate_steps > 0. Collective.
Layouts chooseLayouts(const Comm& world, const Config& cfg);

}  // namespace coloc::coupling
