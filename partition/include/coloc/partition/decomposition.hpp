// coloc/partition/decomposition.hpp — the one Cartesian block decomposition that the fluid and
// the particles share (docs/architecture.md). Rank r owns the CFD cells of its block and the DEM
// bins that cover the same region, so co-location holds by construction.
//
// Blocks are defined by cuts along each axis: block c along axis d owns global cells
// [cuts[d][c], cuts[d][c+1]). The uniform strategy splits N cells over P ranks as evenly as
// possible (the first N mod P blocks get one more cell); the balanced strategy passes its own
// cuts. Cells are the unit: a block edge is always a cell face.
//
// A tiled decomposition (fromBoxes, partition/tiled.hpp) has no process grid: rank r owns any box
// of whole cells, the boxes tile the grid, and the owner of a cell is found by walking the tree
// of cut planes that separates the boxes (O(log P), no per-cell map). On a tiled decomposition
// dims(), coords(), cuts(), neighbour(), rankOfCoords() and coordsOfRank() throw Error: the
// exchanges use the box neighbours (partition/box_halo.hpp) instead.
//
// Face ownership (staggered fields): along axis d, the face with global index f (the low face of
// cell f) belongs to the block that owns cell f. The last face of a non-periodic axis (f = N_d)
// belongs to the last block. On a periodic axis face N_d is face 0.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "coloc/core/comm.hpp"

namespace coloc {

using Int3 = std::array<int, 3>;
using Real3 = std::array<double, 3>;

/// The global box: origin, size, cells, periodicity.
struct GlobalGrid {
  Real3 origin{0, 0, 0};
  Real3 length{1, 1, 1};
  Int3 cells{1, 1, 1};
  std::array<bool, 3> periodic{false, false, false};
  double spacing(int d) const { return length[d] / cells[d]; }
  long long cellCount() const { return 1LL * cells[0] * cells[1] * cells[2]; }
  double cellVolume() const { return spacing(0) * spacing(1) * spacing(2); }
};

class Decomposition {
 public:
  /// Uniform blocks. `dims` = {0,0,0} lets chooseDims choose; a non-zero entry fixes that
  /// axis. Throws ConfigError (key "partition.dims") when the grid cannot hold the blocks.
  static Decomposition uniform(const Comm& world, const GlobalGrid& grid, Int3 dims = {0, 0, 0},
                               int minCells = 1);
  /// Blocks from explicit cuts (each axis: 0 = c_0 < c_1 < ... < c_P = N).
  static Decomposition fromCuts(const Comm& world, const GlobalGrid& grid,
                                std::array<std::vector<int>, 3> cuts);
  /// General boxes: rank r owns the global cells [lo[r], hi[r]). The boxes must tile the grid
  /// and be separable by cut planes (recursive bisection layouts and process grids are);
  /// otherwise ConfigError (key partition.boxes).
  static Decomposition fromBoxes(const Comm& world, const GlobalGrid& grid, std::vector<Int3> lo,
                                 std::vector<Int3> hi);
  /// The process grid the uniform strategy uses for `size` ranks (non-zero entries are kept):
  /// MPI_Dims_create's, the largest count on the axis with the most cells, when the even split
  /// then leaves every block at least `minCells` cells along every axis; otherwise the legal
  /// factorisation with the smallest block surface. No MPI communication (callable for any
  /// rank count). Throws ConfigError naming partition.dims and domain.cells when none is legal.
  static Int3 chooseDims(int size, const GlobalGrid& grid, Int3 dims = {0, 0, 0}, int minCells = 1);
  /// The even split of n cells over p blocks.
  static std::vector<int> evenCuts(int n, int p);

  const Comm& comm() const { return comm_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  const GlobalGrid& grid() const { return grid_; }
  /// True for a layout of general boxes (fromBoxes), false for a process grid.
  bool isTiled() const { return !tree_.empty(); }
  Int3 dims() const;
  Int3 coords() const;
  const std::array<std::vector<int>, 3>& cuts() const;

  /// "2x1x3 blocks" (a process grid) or "7 boxes" (tiled): for progress lines.
  std::string shape() const;

  /// Global cell range [lo, hi) of this block, and its size.
  Int3 lo() const { return lo_; }
  Int3 hi() const { return hi_; }
  Int3 cells() const { return {hi_[0] - lo_[0], hi_[1] - lo_[1], hi_[2] - lo_[2]}; }
  long long ownedCellCount() const;
  /// Physical bounds of this block.
  Real3 blockLo() const;
  Real3 blockHi() const;

  /// Neighbour rank across the low (side = -1) or high (side = +1) face along `d`, with
  /// periodic wrap; MPI_PROC_NULL at a non-periodic box face.
  int neighbour(int d, int side) const;
  /// True when this block touches a non-periodic face of the box (a physical boundary).
  bool atLowBoundary(int d) const { return !grid_.periodic[d] && lo_[d] == 0; }
  bool atHighBoundary(int d) const { return !grid_.periodic[d] && hi_[d] == grid_.cells[d]; }

  int rankOfCoords(Int3 c) const;
  Int3 coordsOfRank(int r) const;
  /// Global cell range of any rank's block.
  Int3 loOf(int r) const;
  Int3 hiOf(int r) const;
  /// Every rank's box, rank order (computed from the cuts on a process grid).
  void boxes(std::vector<Int3>& lo, std::vector<Int3>& hi) const;
  /// Owner of a global cell (wrapped on periodic axes); -1 if outside a non-periodic box.
  int ownerOfCell(Int3 cell) const;
  /// Owner of the face f along axis d in the transverse cell (j, k) (see header comment).
  int ownerOfFace(int d, Int3 face) const;
  /// Owner of a point; a point on the top face of the box belongs to the last block; -1 outside.
  int ownerOfPoint(Real3 x) const;
  /// Global cell containing a point, clamped into the box (no periodic wrap).
  Int3 cellOfPoint(Real3 x) const;

 private:
  Decomposition() = default;
  void build(const Comm& world);
  void requireGrid(const char* what) const;
  int blockAlong(int d, int cell) const;
  // Tiled layouts: the boxes and the tree of cut planes (node: axis, plane, low / high child;
  // a leaf has axis -1 and holds the rank in `low`).
  struct Node {
    int axis = -1, plane = 0, low = 0, high = 0;
  };
  std::vector<Int3> boxLo_, boxHi_;
  std::vector<Node> tree_;
  GlobalGrid grid_;
  std::shared_ptr<MPI_Comm> cart_;
  Comm comm_;
  int rank_ = 0, size_ = 1;
  Int3 dims_{1, 1, 1}, coords_{0, 0, 0}, lo_{0, 0, 0}, hi_{1, 1, 1};
  std::array<std::vector<int>, 3> cuts_;
  std::array<std::array<int, 2>, 3> nbr_{};
};

}  // namespace coloc
