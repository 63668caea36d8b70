// partition/src/prefix_sum.hpp (internal) — summed-volume table of a per-cell cost, for block
// sums in O(1): used by the balanced (balance.cpp) and tiled (tiled.cpp) strategies.
#pragma once

#include <cstddef>
#include <vector>

#include "coloc/partition/decomposition.hpp"

namespace coloc::detail {

/// S(i,j,k) = sum of cost over [0,i) x [0,j) x [0,k).
class PrefixSum {
 public:
  PrefixSum(const GlobalGrid& g, const std::vector<double>& c)
      : nx_(g.cells[0] + 1),
        ny_(g.cells[1] + 1),
        s_(static_cast<std::size_t>(nx_) * ny_ * (g.cells[2] + 1), 0.0) {
    for (int k = 1; k <= g.cells[2]; ++k)
      for (int j = 1; j <= g.cells[1]; ++j)
        for (int i = 1; i <= g.cells[0]; ++i) {
          const double v =
              c[static_cast<std::size_t>((i - 1) + g.cells[0] * ((j - 1) + g.cells[1] * (k - 1)))];
          at(i, j, k) = v + at(i - 1, j, k) + at(i, j - 1, k) + at(i, j, k - 1) -
                        at(i - 1, j - 1, k) - at(i - 1, j, k - 1) - at(i, j - 1, k - 1) +
                        at(i - 1, j - 1, k - 1);
        }
  }
  double box(int i0, int i1, int j0, int j1, int k0, int k1) const {
    return at(i1, j1, k1) - at(i0, j1, k1) - at(i1, j0, k1) - at(i1, j1, k0) + at(i0, j0, k1) +
           at(i0, j1, k0) + at(i1, j0, k0) - at(i0, j0, k0);
  }

 private:
  double& at(int i, int j, int k) { return s_[static_cast<std::size_t>(i + nx_ * (j + ny_ * k))]; }
  double at(int i, int j, int k) const {
    return s_[static_cast<std::size_t>(i + nx_ * (j + ny_ * k))];
  }
  int nx_, ny_;
  std::vector<double> s_;
};

}  // namespace coloc::detail
