// dem/src/neighbour_search.hpp — the neighbour search of the DEM as a part that owns its state
// (as LAMMPS's Neighbor): the bins (bins.hpp), the half Verlet list (neighbours.hpp), the
// contact-history pool (history.hpp) and the rebuild's own int scratch (the (bin, id) re-sort's
// permutation; the destination codes and row cursors of the history packing). It works on the
// particles its owner passes to each call; the sequence of a rebuild (pack, migrate, sort,
// ghosts, lists, keep positions) is the owner's (dem.cpp).
//   bins.cpp        the counting sort by bin, the (bin, id) re-sort of owned particles
//   neighbours.cpp  the half Verlet list build (and the history lookup of its entries)
//   history.cpp     the history packing into rows per owned particle, row compaction
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "bins.hpp"
#include "buffers.hpp"
#include "coloc/dem/dem.hpp"
#include "history.hpp"
#include "neighbours.hpp"

namespace coloc::dem::detail {

/// The walls of the box, [axis][low, high] (true: a wall there).
using WallMask = std::array<std::array<bool, 2>, 3>;

class NeighbourSearch {
 public:
  const Bins& bins() const { return bins_; }
  const NeighbourList& list() const { return list_; }
  const HistoryPool& history() const { return hist_; }

  /// The bins of the block for layout `b` (set-up, once the decomposition is known).
  void setupBins(const GlobalGrid& grid, const BinLayout& b, const Int3& cellLo,
                 const Int3& cellHi) {
    bins_.setup(grid, b, cellLo, cellHi);
  }
  /// The contact-history pool, writable: its rows are written by the owner outside the rebuild
  /// (set-up and restore, outflow removal, migration through the particle exchange) and its
  /// slots taken, freed and updated by the force pass.
  HistoryPool& mutableHistory() { return hist_; }
  /// The history slot of each list entry (list order), writable: the force pass takes a slot
  /// when a contact starts and frees it when it ends.
  int* listSlots() { return list_.slot.data(); }
  /// The same, read only: after a force pass an entry has a slot exactly when it touches.
  const int* listSlots() const { return list_.slot.data(); }
  /// The inner list's masks, one a row (neighbours.hpp), written by a pruning force pass.
  KeepMask* listKeep() { return list_.keep.data(); }

  // The pruned inner list. A force pass over the whole list with a margin > 0 marks in keep the
  // entries whose gap is below it (and those that touch); while no two particles can have
  // closed that gap since, the next passes visit the marked entries only (the others cannot
  // touch: same results, bit for bit). The bound is the sum over the sub-steps of the largest
  // drift of any particle (every rank sums the same global values: moved()); a rebuild, or the
  // bound reaching half the margin (a pair closes at most twice it), ends the inner list.
  /// The prune margin (m; 0: no inner list), set once.
  void setPruneMargin(double m) { margin_ = m; }
  double pruneMargin() const { return margin_; }
  /// Whether the force pass may read the inner list.
  bool innerListValid() const { return innerValid_; }
  /// A force pass pruned the list at the current positions.
  void pruned() {
    innerValid_ = true;
    moved_ = 0;
    ++prunes_;
  }
  /// Pruning passes since construction (the same on every rank).
  long long pruneCount() const { return prunes_; }
  /// Every particle moved at most `d` (m) since the last call (a sub-step's drift, global); the
  /// inner list ends when twice the sum reaches the margin (NaN and inf end it too).
  void moved(double d);

  /// The history pool reduced to the slots the list holds (restore: the rows held every
  /// history twice, under both particles of a pair).
  void compactHistory() { hist_.compact(list_.slot); }

  /// The history pool becomes rows per owned particle of `p` (the format migration carries and
  /// the list build reads), keyed by the partner's global id (walls: -1..-6); `dec`, `nRanks`:
  /// the owner of each particle (a pair bound for two ranks keeps a row under each). `lend`: a
  /// buffer dead during the call (24 bytes a history), in which the histories are gathered.
  void packHistory(const ParticleStore& p, const Decomposition& dec, int nRanks,
                   const Lender& lend);
  /// Owned particles of `p` put in (bin, id) order; the history rows stay in pre-sort order
  /// (the permutation is kept for buildLists).
  void sortByBin(ParticleStore& p);
  /// Every local particle sorted by bin, the half list built (pairs closer than their radii plus
  /// `skin`; walls of `wallOn` close the rows of owned particles), each entry taking its history
  /// from the rows; the rows no entry took are free slots.
  void buildLists(const ParticleStore& p, double skin, const WallMask& wallOn);
  /// The owned positions as the rebuild check's reference (x0), at the end of a rebuild.
  void keepPositions(const ParticleStore& p);
  /// The largest squared displacement of an owned particle since keepPositions (NaN and inf
  /// become the largest double).
  double maxDisplacement2(const ParticleStore& p) const;
  /// Bytes of the rebuild's scratch (capacity).
  std::size_t scratchBytes() const { return cap(scratch_) + cap(candidates_); }

 private:
  Bins bins_;
  NeighbourList list_;
  HistoryPool hist_;
  // sortByBin to the end of buildLists: the (bin, id) re-sort's permutation (scratch_[k]: the
  // history row of particle k); in packHistory: destination codes, then row cursors
  std::vector<int> scratch_;
  // buildLists: the candidates of one row within reach (at most 1 + 13 bins' worth)
  std::vector<int> candidates_;
  double margin_ = 0, moved_ = 0;
  bool innerValid_ = false;
  long long prunes_ = 0;
  // ints of the list's entry array that sortByBin borrows per owned particle (one column
  // element of up to 8 bytes); buildLists' trim keeps at least that many
  static constexpr std::size_t kSortBufferInts = 2;
};

}  // namespace coloc::dem::detail
