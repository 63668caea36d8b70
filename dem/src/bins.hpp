// dem/src/bins.hpp — the DEM's bins: the block's share of the global bin grid (bin edges are
// cell edges), the owner rule, and the one counting sort by bin that both the (bin, id) re-sort
// of owned particles and the neighbour-list build use.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "buffers.hpp"
#include "coloc/dem/dem.hpp"

namespace coloc::dem::detail {

struct Bins {
  Real3 origin{}, L{}, bs{}, lo{}, hi{};  // box origin and length, bin edge, block bounds
  std::array<bool, 3> periodic{};
  std::array<long long, 3> NbG{}, binLo{}, binHi{};              // global bins, block's range
  std::array<long long, 3> binSplit{1, 1, 1}, binMult{1, 1, 1};  // bin = cell/split or mult cells
  Int3 nb{}, nbx{};  // local bins, and with one ghost layer on each side
  // the last sort: start of every bin's run, items in (bin, id) order (an item's bin is the run
  // it lies in)
  std::vector<int> binStart, binItems;

  /// The block's bins for a layout (dec: the block).
  void setup(const GlobalGrid& grid, const BinLayout& b, const Int3& cellLo, const Int3& cellHi);
  std::size_t bytes() const { return cap(binStart) + cap(binItems); }
  std::size_t count() const { return static_cast<std::size_t>(nbx[0]) * nbx[1] * nbx[2]; }
  long long gbinRaw(double x, int d) const {
    const double s = std::floor((x - origin[d]) / bs[d]);
    if (!(s > -1e15)) return -(1LL << 50);
    if (!(s < 1e15)) return 1LL << 50;
    return static_cast<long long>(s);
  }
  long long gbinClamped(double x, int d) const {
    return std::clamp(gbinRaw(x, d), 0LL, NbG[d] - 1);
  }
  /// The owner rule: the clamped global bin of x lies in this block.
  bool owns(const double* x) const {
    for (int d = 0; d < 3; ++d) {
      const long long b = gbinClamped(x[d], d);
      if (b < binLo[d] || b >= binHi[d]) return false;
    }
    return true;
  }
  /// The rank whose block owns x by this rule (x wrapped into the box on periodic axes).
  int ownerRank(const Decomposition& dec, const double* x) const {
    Int3 cell{};
    for (int d = 0; d < 3; ++d) {
      const long long b = gbinClamped(x[d], d);
      cell[d] = static_cast<int>(binSplit[d] > 1 ? b / binSplit[d] : b * binMult[d]);
    }
    return dec.ownerOfCell(cell);
  }
  /// Local bin (with the ghost layer) of a position: an owned particle clamped into the block, a
  /// ghost into the ghost layer.
  int localBin(double x, double y, double z, bool owned) const {
    const double c[3] = {x, y, z};
    int b[3];
    for (int d = 0; d < 3; ++d) {
      const long long lb = gbinRaw(c[d], d) - binLo[d];
      b[d] = static_cast<int>(owned ? std::clamp(lb, 0LL, static_cast<long long>(nb[d] - 1))
                                    : std::clamp(lb, -1LL, static_cast<long long>(nb[d]))) +
             1;
    }
    return b[0] + nbx[0] * (b[1] + nbx[1] * b[2]);
  }
  /// The counting sort: particles [0, n) (the first n of `p`, owned first) by their local bin
  /// into binStart and `items` (n ints: by bin, then by index); then the run of every bin put in id
  /// order unless its last item is below `sortedBelow` (owned particles already in (bin, id)
  /// order need no sort). `scratch`, `binOf`: grow-only int buffers whose contents are lost
  /// (binOf: every item's bin during the sort; the callers lend a buffer that is dead then).
  void sort(const ParticleStore& p, std::size_t n, int* items, std::vector<int>& scratch,
            std::vector<int>& binOf, int sortedBelow);
};

}  // namespace coloc::dem::detail
