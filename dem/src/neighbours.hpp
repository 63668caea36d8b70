// dem/src/neighbours.hpp — the half Verlet list of the DEM (rows in canonical (bin, id) order,
// see neighbours.cpp) and the positions at its build (the rebuild criterion).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "buffers.hpp"

namespace coloc::dem::detail {

/// The inner list's mask of a row: bit k for entry k of the row; entries from kKeepBits on are
/// always in the inner list.
using KeepMask = std::uint16_t;
inline constexpr int kKeepBits = 16;
static_assert(sizeof(KeepMask) * 8 == kKeepBits);

struct NeighbourList {
  std::vector<int> rowStart, nbr;  // row q (holder binItems[q]): partners nbr[rowStart[q]...]
  std::vector<int> slot;           // per entry: its history in the pool (-1: none)
  // per row: the entries of the pruned inner list (bit k: entry rowStart[q] + k), written by a
  // force pass over the whole list (force_pass.hpp)
  std::vector<KeepMask> keep;
  std::size_t bytes() const { return cap(rowStart) + cap(nbr) + cap(slot) + cap(keep); }
};

}  // namespace coloc::dem::detail
