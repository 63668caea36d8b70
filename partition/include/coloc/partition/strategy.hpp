// coloc/partition/strategy.hpp — the partition strategies (class PartitionStrategy, one object
// each): the blocks each chooses, for any rank count and without a communicator. A run builds its
// Decompositions from these (coupling::chooseLayouts, re-balance), and `coloc check` and
// `coloc plan` evaluate them for rank counts they do not run: one code path for all three.
//
//   uniform      chooseDims (MPI_Dims_create's grid where legal) and even cuts;
//   balanced     balanceBlocks on the modelled cost of every cell (partition/balance.hpp);
//   independent  the fluid on the uniform blocks, the DEM on blocks balanced by particle count,
//                on a process grid other than the fluid's when one fits;
//   tiled        one box per rank by recursive bisection of the modelled cost (partition/
//                tiled.hpp): no process grid, so boxes, not Blocks (tiledStrategy). Runs
//                build Decomposition::fromBoxes from it (coupling/layouts).
//
// Ranks are numbered as MPI_Cart_create numbers them without reordering: row-major over the
// block coordinates, z fastest.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "coloc/core/run_config.hpp"
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

/// The uniform strategy's blocks.
Blocks uniformBlocks(const StrategyInput& in);

/// The work of every global cell (x fastest) a strategy places its blocks on: the modelled cost
/// (partition.cost.*: a cell and the particles in it), the particles it holds (the independent
/// strategy balances its DEM blocks by count) and the modelled cost of a halo cell (the tiled
/// surface term, partition.cost.halo_cell). A strategy reads only what it needs: `cost` may be
/// empty for uniform and independent, `count` for all but independent.
struct CellWork {
  const std::vector<double>& cost;
  const std::vector<double>& count;
  double haloCell = 0.0;
};

/// The layout a strategy chooses for StrategyInput::ranks ranks, computed on one process.
struct StrategyLayout {
  /// Rank r's box of cells, of the fluid and of the particles (the same boxes but in independent
  /// partitions, whose particles have blocks of their own).
  BoxLayout fluid, particles;
  /// A process-grid layout's blocks (unset for tiled boxes); particleBlocks only where the
  /// particles have blocks of their own.
  std::optional<Blocks> fluidBlocks, particleBlocks;
  double modelledImbalance = 1.0;  // max / mean block cost under what it balanced (uniform: 1)
  double uniformImbalance = 1.0;   // the uniform blocks' under the same cost (NaN: none fits)
  double maxCost = 0.0, meanCost = 0.0;  // largest and mean block (box) cost, same cost
  bool isGrid() const { return fluidBlocks.has_value(); }
};

/// The boxes of a process grid's blocks (rank r: [b.lo(r), b.hi(r))).
BoxLayout boxesOf(const GlobalGrid& g, const Blocks& b);
/// A process-grid layout of `fluid` blocks, and of the particles' own blocks when given; costs
/// unset.
StrategyLayout blocksLayout(const GlobalGrid& g, const Blocks& fluid,
                            const std::optional<Blocks>& particles = std::nullopt);
/// The layout of a live decomposition (its blocks too, when it has a process grid); costs unset.
StrategyLayout layoutOf(const Decomposition& dec);

/// A partition strategy: how the blocks of the fluid and of the particles are chosen for N ranks.
/// One object per strategy (PartitionStrategy::named); a run (coupling::chooseLayouts, re-balance,
/// restart), `coloc check` and `coloc plan` all ask it, so they cannot disagree. Adding a
/// strategy is one class in partition/src/strategy.cpp and one line in PartitionStrategy::all()
/// (CONTRIBUTING.md).
class PartitionStrategy {
 public:
  virtual ~PartitionStrategy() = default;
  /// The partition.strategy value.
  virtual std::string_view name() const = 0;
  /// Whether its blocks sit on the modelled cost (partition.cost.*, measured first when
  /// partition.calibrate_steps > 0): reports give the weights and imbalances, and re-balancing
  /// (partition.rebalance_interval) moves them.
  virtual bool balancesCost() const { return false; }
  /// Whether the particles have blocks of their own, balanced by particle count (CellWork::count).
  virtual bool ownParticleBlocks() const { return false; }
  /// Whether its layouts are process grids (Decomposition::fromCuts; a checkpoint stores the
  /// cuts) or tiled boxes (fromBoxes; a checkpoint stores the boxes).
  virtual bool gridLayout() const { return true; }
  /// Whether `coloc plan` evaluates it when no --strategy is named.
  virtual bool plannedByDefault() const { return true; }

  /// The layout before any cost is known: the uniform blocks (tiled: boxes of equal cell
  /// counts). A fluid-only run keeps it; the cost probe and the calibration run on it.
  virtual StrategyLayout startLayout(const StrategyInput& in, double haloCell) const;
  /// The layout on `work`. Throws ConfigError where the case has no legal layout.
  virtual StrategyLayout layout(const StrategyInput& in, const CellWork& work) const = 0;
  /// `current` (layoutOf a live decomposition) measured as layout() measures its own blocks:
  /// its modelledImbalance, uniformImbalance, maxCost and meanCost under `work` (the verdict of a
  /// re-balance). Throws Error for a strategy that does not balance the cost.
  virtual StrategyLayout evaluate(StrategyLayout current, const StrategyInput& in,
                                  const CellWork& work) const;
  /// The layout of a run in `mode`: startLayout for a fluid-only run, else layout().
  StrategyLayout layoutFor(RunMode mode, const StrategyInput& in, const CellWork& work) const;

  /// The strategy called `name`; ConfigError naming `key` and listing the strategies otherwise.
  static const PartitionStrategy& named(std::string_view name,
                                        const std::string& key = "partition.strategy");
  /// Every strategy, in the order reports and `coloc check` list them.
  static std::span<const PartitionStrategy* const> all();
  /// Their names, in that order.
  static std::vector<std::string> names();
};

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
