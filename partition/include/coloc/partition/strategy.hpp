// coloc/partition/strategy.hpp — the blocks each partition strategy chooses, as cuts, for any
// rank count and without a communicator. A run builds its Decompositions from these
// (coupling::Simulation::chooseLayouts), and `coloc plan` evaluates them for rank counts it does
// not run: one code path for both.
//
//   uniform      chooseDims (MPI_Dims_create's grid where legal) and even cuts;
//   balanced     balanceBlocks on the modelled cost of every cell (partition/balance.hpp);
//   independent  the fluid on the uniform blocks, the DEM on blocks balanced by particle count,
//                on a process grid other than the fluid's when one fits;
//   tiled        one box per rank by recursive bisection of the modelled cost (partition/
//                tiled.hpp): no process grid, so not Blocks (tiledStrategy; chooseBlocks
//                refuses it). Runs build Decomposition::fromBoxes from it (coupling/layouts).
//
// Ranks are numbered as MPI_Cart_create numbers them without reordering: row-major over the
// block coordinates, z fastest.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "coloc/partition/balance.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/tiled.hpp"

namespace coloc {

/// A Cartesian block layout: process grid and cuts (block c along d owns [cuts[d][c],
/// cuts[d][c+1])).
struct Blocks {
  Int3 dims{1, 1, 1};
  std::array<std::vector<int>, 3> cuts;
  int size() const { return dims[0] * dims[1] * dims[2]; }
  Int3 coordsOf(int rank) const {
    return {rank / (dims[1] * dims[2]), (rank / dims[2]) % dims[1], rank % dims[2]};
  }
  int rankOf(Int3 c) const { return (c[0] * dims[1] + c[1]) * dims[2] + c[2]; }
  Int3 lo(int rank) const;
  Int3 hi(int rank) const;
  /// Neighbour across the low (side -1) or high (+1) face along d, periodic wrap; -1 at a
  /// non-periodic box face (MPI_Cart_shift's MPI_PROC_NULL).
  int neighbour(const GlobalGrid& g, int rank, int d, int side) const;
  /// Block index along d of a global cell (0 <= cell < N_d).
  int blockAlong(int d, int cell) const;
};

/// What the strategies need besides the cost: the rank count and the case's constraints.
struct StrategyInput {
  GlobalGrid grid;
  int ranks = 1;
  Int3 dims{0, 0, 0};     // partition.dims (0: free)
  Int3 demDims{0, 0, 0};  // partition.dem_dims (independent)
  int minCells = 2;       // thinnest block (processGridFromConfig's rule)
  int granularity = 1;    // cuts on multiples of this many cells (particles.bin_cells)
};

struct StrategyBlocks {
  std::string strategy;
  Blocks fluid;                     // the co-located blocks (uniform, balanced) or the fluid's
  std::optional<Blocks> particles;  // independent: the DEM's own blocks
  double modelledImbalance = 1.0;   // balanced: max/avg modelled block cost
  double uniformImbalance = 1.0;    // balanced: the same for the uniform blocks
};

/// The uniform strategy's blocks.
Blocks uniformBlocks(const StrategyInput& in);

/// The blocks of `strategy` ("uniform", "balanced", "independent"). `cost`: the modelled cost of
/// every global cell (x fastest; balanced), `count`: particles per global cell (independent);
/// either may be empty where the strategy does not read it. Throws ConfigError.
StrategyBlocks chooseBlocks(const std::string& strategy, const StrategyInput& in,
                            const std::vector<double>& cost, const std::vector<double>& count);

/// The tiled strategy's boxes on `cost` (one value per global cell): the balanced strategy's
/// thinnest block (max(2, minCells)) and granularity; `surfaceCost` per halo cell of a box
/// (2 layers, the fluid's ghosts). The bisection's boxes, or the balanced strategy's blocks as
/// boxes where their largest cost is lower by more than 0.1 %, or within 0.1 % with fewer halo
/// cells. Throws ConfigError.
TiledLayout tiledStrategy(const StrategyInput& in, const std::vector<double>& cost,
                          double surfaceCost = 0.0);

/// Blocks of a live decomposition.
Blocks blocksOf(const Decomposition& dec);

}  // namespace coloc
