// Helpers of the tests on tiled layouts: a cost heaped in one corner of the grid, so that the
// bisection's boxes form no process grid (neighbours across edges and corners).
#pragma once

#include <cstddef>
#include <vector>

#include "coloc/partition/tiled.hpp"

namespace coloc::test {

/// Cost 1 per cell, plus `extra` in the cells with i < heap[0], j < heap[1] and k < heap[2]
/// (x fastest, as tiledBoxes reads it).
inline std::vector<double> heapedCost(const GlobalGrid& g, Int3 heap, double extra) {
  std::vector<double> cost(static_cast<std::size_t>(g.cellCount()), 1.0);
  for (int k = 0; k < g.cells[2]; ++k)
    for (int j = 0; j < g.cells[1]; ++j)
      for (int i = 0; i < g.cells[0]; ++i)
        if (i < heap[0] && j < heap[1] && k < heap[2])
          cost[static_cast<std::size_t>(i + g.cells[0] * (j + g.cells[1] * k))] += extra;
  return cost;
}

}  // namespace coloc::test
