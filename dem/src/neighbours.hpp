// dem/src/neighbours.hpp — the half Verlet list of the DEM (rows in canonical (bin, id) order,
// see neighbours.cpp) and the positions at its build (the rebuild criterion).
#pragma once

#include <array>
#include <vector>

#include "buffers.hpp"

namespace coloc::dem::detail {

struct NeighbourList {
  std::vector<int> rowStart, nbr;  // row q (holder binItems[q]): partners nbr[rowStart[q]...]
  std::vector<int> slot;           // per entry: its history in the pool (-1: none)
  std::size_t bytes() const { return cap(rowStart) + cap(nbr) + cap(slot); }
};

}  // namespace coloc::dem::detail
