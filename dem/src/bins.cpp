// dem/src/bins.cpp — the bins: the block's share of the global bin grid, the one counting sort by
// bin, the (bin, id) re-sort of owned particles.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <type_traits>

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
  // applied column by column through a buffer: gathered (independent loads; a walk along the
  // permutation's cycles is a chain of dependent ones, a cache miss each where the cycles are
  // long), then copied back. The buffer is the neighbour list's entry array, dead until its build
  // and kept at kSortBufferInts a particle: a bed's list needs more (~5 entries a particle), so
  // memory grows only where the list is shorter (up to 8 bytes a particle). Bytes are moved with
  // memcpy: the buffer's elements are ints.
  const std::size_t bufInts = kSortBufferInts * n;
  ensure(list_.nbr, bufInts);
  if (list_.nbr.size() < bufInts) list_.nbr.resize(bufInts);
  auto* const buf = reinterpret_cast<unsigned char*>(list_.nbr.data());
  const auto apply = [&](auto& vec) {
    using T = typename std::decay_t<decltype(vec)>::value_type;
    static_assert(std::is_trivially_copyable_v<T> && sizeof(T) <= kSortBufferInts * sizeof(int));
    T* const v = vec.data();
    for (std::size_t k = 0; k < n; ++k) std::memcpy(buf + k * sizeof(T), v + perm[k], sizeof(T));
    if (n > 0) std::memcpy(v, buf, n * sizeof(T));
  };
  detail::forEachColumn(p, apply);
  // the history rows stay in pre-sort order: buildLists reads row perm[k] for particle k
}

}  // namespace coloc::dem
