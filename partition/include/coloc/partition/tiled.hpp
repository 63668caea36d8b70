// coloc/partition/tiled.hpp — tiled co-located layouts: each rank owns one box of whole cells
// (and so of whole DEM bins), the boxes tile the grid, and they need not form a process grid.
//
// tiledBoxes() finds the boxes by recursive coordinate bisection (RCB) of a per-cell cost: a
// region given p ranks is split in two by one plane of cells, and its ranks are split with it.
// Every legal plane of every axis is tried (axes longest first, in cells), each with the rank
// split p/2 | p - p/2 and with the split nearest to the plane's share of the cost; the plane and
// split whose larger cost per rank is smallest win (ties: the first tried). Splitting the ranks
// by the cost, not always in halves, lets a bed holding most of the work take most of the ranks;
// it can also leave a side with a share its whole cells divide badly, which the score of one
// cut cannot see. So at every region the 4 best splits by score are each carried out greedily
// to the end and the one whose largest box is cheapest is taken (never worse than the greedy
// choice); and the whole bisection runs three times, the rank split allowed 0, p/4 and p ranks
// from halving, keeping the layout whose largest box is cheapest (within 0.1 %: the one with
// the fewest halo cells).
// The cost of a region is the sum of its cells' cost plus a surface term, `surfaceCost` per halo
// cell of the region (the ghost and halo work a box pays for its neighbours). Every box keeps
// at least `minCells` cells along each axis (the ghost width; an axis thinner than that stays
// whole) and every cut lies on a multiple of `granularity` cells (DEM bins spanning several
// cells stay whole); a split is legal only where both sides can hold their ranks' boxes. A grid
// that cannot hold `ranks` boxes at all is refused (ConfigError). No MPI: the run and `coloc
// plan` call it alike.
//
// Ranks are numbered in the order of the bisection tree: the low side of every cut first.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc {

/// A layout of general boxes: rank r owns the global cells [box[r].lo, box[r].hi).
struct BoxLayout {
  GlobalGrid grid;
  std::vector<IndexBox> box;
  int size() const { return static_cast<int>(box.size()); }
  /// The owner of every global cell (x fastest); throws Error when the boxes do not tile the
  /// grid (a cell owned twice or not at all).
  std::vector<int> ownerMap() const;
  /// Along each axis, the distinct box bounds, ascending (0 and N included): the planes where
  /// DEM bins must have edges.
  std::array<std::vector<int>, 3> cutPlanes() const;
};

/// The boxes of a decomposition (a process grid's blocks, or a tiled layout's boxes).
BoxLayout boxLayoutOf(const Decomposition& dec);
/// The tiled decomposition of `comm`'s ranks on a layout's boxes (Decomposition::fromBoxes).
Decomposition decompositionOf(const Comm& comm, const BoxLayout& l);

struct TiledOptions {
  int minCells = 2;        // thinnest box along an axis (an axis thinner than this stays whole)
  int granularity = 1;     // box bounds on multiples of this many cells (or on N)
  double surfaceCost = 0;  // cost per halo cell of a box
  int ghost = 2;           // halo layers counted by the surface term
};

/// Weights of the per-cell cost: perCell + perParticle x particles + perContact x contacts.
struct TiledCostModel {
  double perCell = 1.0, perParticle = 0.0, perContact = 0.0;
};

struct TiledLayout {
  BoxLayout layout;
  std::vector<double> boxCost;  // per rank: its cells' cost + surfaceCost x halo cells
  double maxCost = 0, avgCost = 0;
  double imbalance() const { return avgCost > 0 ? maxCost / avgCost : 1.0; }
};

/// Halo cells of box b: cells within `ghost` layers of it (faces, edges, corners) that lie in
/// the domain or across a periodic face; those beyond a non-periodic wall do not count.
long long haloCells(const GlobalGrid& g, const IndexBox& b, int ghost);

/// Per-cell cost (x fastest) from per-cell particle and contact counts (either may be empty).
std::vector<double> tiledCellCost(const GlobalGrid& g, const TiledCostModel& m,
                                  std::span<const double> particles,
                                  std::span<const double> contacts);

/// The RCB boxes of `ranks` ranks on `cost` (one value per global cell, x fastest).
TiledLayout tiledBoxes(const GlobalGrid& grid, const std::vector<double>& cost, int ranks,
                       const TiledOptions& opt = {});

/// A floor under the largest box cost of any layout whose boxes keep at least `minCells` cells
/// along each axis (min(minCells, N) on a thinner axis): every box holding cell c holds a box of
/// exactly that size holding c, so it costs at least the cheapest such box; the floor is the
/// largest of these over the cells. (Floor / mean cost: the imbalance no layout can beat.)
double boxCostFloor(const GlobalGrid& grid, const std::vector<double>& cost, int minCells);

/// Box costs and imbalance of any box layout under the same cost (the surface term included).
void evaluateBoxes(const std::vector<double>& cost, const TiledOptions& opt, TiledLayout& l);

}  // namespace coloc
