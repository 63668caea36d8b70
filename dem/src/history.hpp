// dem/src/history.hpp — the contact-history pool of the DEM.
//
// hS holds 3 doubles per slot. Between rebuilds the slots are used by the neighbour-list entries
// of touching pairs (NeighbourList::slot), with a free list; from the packing at a rebuild to the
// next list build they are rows per owned particle (hStart, key hKey = the partner's global id,
// walls -1..-6), which migration carries; the list build then takes its entries' slots from the
// rows (no second pool).
//
// The keys are needed only from the packing to the list build, and the positions at the last
// sort (x0, the rebuild check's reference) only between rebuilds: the two share one array, hKey
// (keys as doubles, exact for ids below 2^53, as in every particle row), so the keys cost no
// memory of their own. The rebuild writes x0 after the list build (Impl::keepPositions).
#pragma once

#include <cstdint>
#include <vector>

#include "buffers.hpp"
#include "coloc/dem/dem.hpp"

namespace coloc::dem::detail {

struct HistoryPool {
  std::vector<int> hStart;
  std::vector<double> hKey;  // keys of the rows (a rebuild), else x0: 3 columns of nOwned
  std::vector<double> hS;
  std::vector<int> freeSlots;

  /// Slots in the pool (live and free).
  std::size_t slots() const { return hS.size() / 3; }
  /// The rebuild check's reference positions, column d (valid between rebuilds).
  const double* x0(int d, std::size_t n) const {
    return hKey.data() + static_cast<std::size_t>(d) * n;
  }

  /// A slot for a contact that starts (zero shear), and back to the free list. Out of line
  /// (history.cpp): rare, and called from the force pass of every instruction set.
  [[gnu::cold]] int newSlot();
  void freeSlot(int s);
  /// Row i's histories [h0, h1) moved down to hw on (rows before it leave); hStart[w] = hw.
  void keepRows(std::size_t w, int h0, int h1, int& hw);
  /// The rows end after `rows` particles and hw histories.
  void truncate(std::size_t rows, int hw);
  /// The live slots of `slot` (list entries, -1: none) packed densely, renumbered; no free list.
  void compact(std::vector<int>& slot);
  std::size_t bytes() const { return cap(hStart) + cap(hKey) + cap(hS) + cap(freeSlots); }
};

/// Owned row i of `p` kept as row w (w <= i) while rows before it leave (migration, outflow), its
/// packed contact histories [h0, h1) moved down to hw on.
void keepRow(ParticleStore& p, HistoryPool& hist, std::size_t i, std::size_t w, int h0, int h1,
             int& hw);

}  // namespace coloc::dem::detail
