// dem/src/bins.cpp — the bins: the block's share of the global bin grid, the one counting sort by
// bin, the (bin, id) re-sort of owned particles.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "neighbour_search.hpp"
#include "rows.hpp"

namespace coloc::dem {

using namespace detail;

void Bins::setup(const GlobalGrid& grid, const BinLayout& b, const Int3& cellLo,
                 const Int3& cellHi) {
  for (int d = 0; d < 3; ++d) {
    origin[d] = grid.origin[d];
    L[d] = grid.length[d];
    periodic[d] = grid.periodic[d];
    bs[d] = b.size[d];
    binSplit[d] = b.split[d];
    binMult[d] = b.multiple[d];
    NbG[d] = b.globalBins[d];
    binLo[d] = b.blockBinLo(d, cellLo[d]);
    binHi[d] = b.blockBinLo(d, cellHi[d]);
    nb[d] = static_cast<int>(binHi[d] - binLo[d]);
    nbx[d] = nb[d] + 2;
    lo[d] = b.lo(grid, d, binLo[d]);
    hi[d] = b.hi(grid, d, binHi[d]);
  }
}

void Bins::sort(const ParticleStore& p, std::size_t n, int* items, std::vector<int>& scratch,
                std::vector<int>& binOf, int sortedBelow) {
  const std::size_t nBins = count();
  const double* X = p.x[0].data();
  const double* Y = p.x[1].data();
  const double* Z = p.x[2].data();
  ensure(binOf, n);
  binOf.resize(n);
  binStart.assign(nBins + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    binOf[i] = localBin(X[i], Y[i], Z[i], i < p.nOwned);
    ++binStart[static_cast<std::size_t>(binOf[i]) + 1];
  }
  for (std::size_t b = 0; b < nBins; ++b) binStart[b + 1] += binStart[b];
  scratch.assign(binStart.begin(), binStart.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    items[static_cast<std::size_t>(scratch[static_cast<std::size_t>(binOf[i])]++)] =
        static_cast<int>(i);
  const std::int64_t* id = p.id.data();
  for (std::size_t b = 0; b < nBins; ++b) {
    const int a = binStart[b], e = binStart[b + 1];
    if (e - a > 1 && items[static_cast<std::size_t>(e - 1)] >= sortedBelow)
      std::sort(items + a, items + e, [id](int u, int v) {
        return id[static_cast<std::size_t>(u)] < id[static_cast<std::size_t>(v)];
      });
  }
}

void NeighbourSearch::sortByBin(ParticleStore& p) {
  // owned particles in (bin, id) order: perm[k] is the particle that goes to position k
  const std::size_t n = p.nOwned;
  ensure(scratch_, n);
  scratch_.resize(n);
  int* const perm = scratch_.data();
  bins_.sort(p, n, perm, list_.nbr, list_.slot, 0);  // the list is dead until its build
  // applied in place, cycle by cycle (no scratch array: 16 bytes per particle less); a visited
  // position is marked by complementing its perm entry, restored after each array
  const auto apply = [&](auto& vec) {
    for (std::size_t s = 0; s < n; ++s) {
      if (perm[s] < 0) continue;
      auto tmp = vec[s];
      std::size_t k = s;
      for (;;) {
        const auto src = static_cast<std::size_t>(perm[k]);
        perm[k] = ~perm[k];
        if (src == s) {
          vec[k] = tmp;
          break;
        }
        vec[k] = vec[src];
        k = src;
      }
    }
    for (std::size_t k = 0; k < n; ++k) perm[k] = ~perm[k];
  };
  detail::forEachColumn(p, apply);
  // the history rows stay in pre-sort order: buildLists reads row perm[k] for particle k
}

}  // namespace coloc::dem
