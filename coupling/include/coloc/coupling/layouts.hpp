// coloc/coupling/layouts.hpp — the blocks a run uses (Layouts), the case's constraints on them
// and the cost probe: where the case's particles start, without a solver.
//
// The strategies themselves are in partition/strategy.hpp (chooseBlocks, for any rank count);
// here they meet a live communicator (chooseBlocksOnRoot) and the case's particles
// (probeParticles: dem::caseParticles, the run's own generator, no DemSolver). The run's
// Simulation::chooseLayouts and `coloc check` use the same probe.
#pragma once

#include <array>
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
/// run.mode, particles.bin_cells): what chooseBlocks (partition/strategy.hpp) takes.
StrategyInput strategyInput(const Config& cfg, int ranks);
/// chooseBlocks on rank 0, which alone holds `cost` (cellCostsOnRoot; the particles per cell
/// when `costIsCount`, for the independent strategy), and the result on every rank. Collective;
/// an error of the root is raised on every rank.
StrategyBlocks chooseBlocksOnRoot(const Comm& comm, const std::string& strategy,
                                  const StrategyInput& in, const std::vector<double>& cost,
                                  bool costIsCount);

/// The tiled strategy on rank 0, which alone holds `cost` (one value per global cell): the boxes
/// of tiledStrategy (surface term partition.cost.halo_cell), sent to every rank (6 ints a rank),
/// as a tiled Decomposition; modelledImbalance is that of the boxes, uniformImbalance that of
/// the uniform blocks under the same cost. Collective; an error of the root is raised on every
/// rank. With `current` (a re-balance), also `verdict` = {the current boxes' imbalance, the
/// gain: their largest box cost / the new boxes'} under the same cost and surface term.
Layouts tiledLayoutsOnRoot(const Comm& comm, const Config& cfg, const std::vector<double>& cost,
                           const CostModel& model, const Decomposition* current = nullptr,
                           std::array<double, 2>* verdict = nullptr);

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
