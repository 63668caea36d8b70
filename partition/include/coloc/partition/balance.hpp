// coloc/partition/balance.hpp — load-balanced co-located blocks.
//
// The balanced strategy keeps one Cartesian process grid for both physics (so co-location holds
// by construction) but places the cuts along each axis where the work is, not where the cells
// are. The work of a cell is modelled as
//     cost(cell) = w_cell + w_particle * (particles whose centre lies in the cell)
// with weights measured from the phase timers (seconds per cell-step and per particle-step) or
// given in the case. A Cartesian grid means separable cuts: the cuts along x are the same for
// every y-z column of blocks. They are chosen by
//   1. multi-section of the marginal cost along each axis (equal shares),
//   2. local refinement: moving single cuts while the largest block cost drops,
// for every factorisation of the rank count into a process grid, keeping the grid whose largest
// block cost is smallest. Cuts stay on multiples of `granularity` cells (DEM bins spanning several
// cells stay whole) and blocks keep at least `minCells` cells along each axis (ghost layers).
#pragma once

#include <array>
#include <span>
#include <vector>

#include "coloc/partition/decomposition.hpp"

namespace coloc {

struct CostModel {
  double perCell = 1.0;      // seconds (or any unit) per cell per step
  double perParticle = 0.0;  // same unit per particle per step
};

struct BalancedLayout {
  Int3 dims{1, 1, 1};
  std::array<std::vector<int>, 3> cuts;
  double maxBlockCost = 0, avgBlockCost = 0;
  double imbalance() const { return avgBlockCost > 0 ? maxBlockCost / avgBlockCost : 1.0; }
};

/// Global cost of every cell (x fastest), from this rank's particle centres; collective
/// (an allreduce of one value per global cell).
std::vector<double> cellCosts(const Decomposition& dec, std::span<const double> x,
                              std::span<const double> y, std::span<const double> z,
                              const CostModel& model);

/// The same cost, on rank 0 only (empty elsewhere): each rank sends the cells of its own block
/// (and the few cells outside it where a particle's centre lies) to rank 0, so that no rank but
/// the root holds or receives anything of the global cell count. Collective (a gather). Equal to
/// cellCosts() bit for bit where each cell's particles are on one rank.
std::vector<double> cellCostsOnRoot(const Decomposition& dec, std::span<const double> x,
                                    std::span<const double> y, std::span<const double> z,
                                    const CostModel& model);

/// Cost of the largest block and the mean block cost of a layout.
void evaluateLayout(const GlobalGrid& grid, const std::vector<double>& cost, BalancedLayout& l);

/// Best separable layout over all process grids of `ranks` (or only `fixedDims` where non-zero).
BalancedLayout balanceBlocks(const GlobalGrid& grid, const std::vector<double>& cost, int ranks,
                             int minCells, int granularity, Int3 fixedDims = {0, 0, 0});

}  // namespace coloc
