// dem/src/history.hpp — the contact-history pool of the DEM.
//
// hS holds 3 doubles per slot. Between rebuilds the slots are used by the neighbour-list entries
// of touching pairs (NeighborList::slot), with a free list; from the packing at a rebuild to the
// next list build they are rows per owned particle (hStart, key hId = the partner's global id,
// walls -1..-6), which migration carries; the list build then takes its entries' slots from the
// rows (no second pool).
#pragma once

#include <cstdint>
#include <vector>

#include "buffers.hpp"

namespace coloc::dem::detail {

struct HistoryPool {
  std::vector<int> hStart;
  std::vector<std::int64_t> hId;
  std::vector<double> hS;
  std::vector<int> freeSlots;

  [[gnu::noinline, gnu::cold]] int newSlot() {
    std::size_t s;
    if (!freeSlots.empty()) {
      s = static_cast<std::size_t>(freeSlots.back());
      freeSlots.pop_back();
    } else {
      s = hId.size();
      ensure(hId, s + 1);
      hId.push_back(0);
      ensure(hS, 3 * s + 3);
      hS.resize(3 * s + 3);
    }
    hS[3 * s] = hS[3 * s + 1] = hS[3 * s + 2] = 0;
    return static_cast<int>(s);
  }
  [[gnu::noinline]] void freeSlot(int s) {
    ensure(freeSlots, freeSlots.size() + 1);
    freeSlots.push_back(s);
  }
  /// Row i's histories [h0, h1) moved down to hw on (rows before it leave); hStart[w] = hw.
  void keepRows(std::size_t w, int h0, int h1, int& hw);
  /// The rows end after `rows` particles and hw histories.
  void truncate(std::size_t rows, int hw);
  /// The live slots of `slot` (list entries, -1: none) packed densely, renumbered; no free list.
  void compact(std::vector<int>& slot);
  std::size_t bytes() const { return cap(hStart) + cap(hId) + cap(hS) + cap(freeSlots); }
};

}  // namespace coloc::dem::detail
