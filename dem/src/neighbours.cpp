// dem/src/neighbours.cpp — the half Verlet list in canonical (bin, id) order, and the
// contact-history lookup of its entries.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "neighbour_search.hpp"

namespace coloc::dem {

using namespace detail;

void NeighbourSearch::buildLists(const ParticleStore& p, double skin, const WallMask& wallOn) {
  const std::size_t nAll = p.size(), n = p.nOwned;
  const int* const perm = scratch_.data();  // sortByBin's
  // every local particle in (bin, id) order (owned clamped into the block, ghosts into the
  // ghost layer; the owned ones are in that order already)
  ensure(bins_.binItems, nAll);
  bins_.binItems.resize(nAll);
  // the list's arrays as the sort's scratch (rebuilt below)
  bins_.sort(p, nAll, bins_.binItems.data(), list_.nbr, list_.slot, static_cast<int>(n));
  // Half list_. binItems is every local particle in (bin, id) order: the canonical key K (the
  // bin's (z, y, x) position, unwrapped across periodic faces, then the global id) orders the
  // holders the same way at any rank count. The row of holder a lists the partners b with
  // K_b > K_a: the rest of a's bin, then the 13 forward stencil bins in increasing index, each
  // in increasing id; at least one of a, b is owned (ghost holders list owned partners only).
  // Walls close the rows of owned particles.
  ensure(list_.rowStart, nAll + 1);
  list_.rowStart.resize(nAll + 1);
  list_.nbr.clear();
  list_.slot.clear();
  const int sy = bins_.nbx[0], sz = bins_.nbx[0] * bins_.nbx[1];
  // The 13 forward bins as runs of bins adjacent in (z, y, x) order, so in binItems: the next bin
  // in x (after the rest of the holder's own bin), then the rows (dy, dz) = (1, 0), (-1, 1),
  // (0, 1), (1, 1), each the three bins dx = -1, 0, 1 (clipped at the grid's ends). The same
  // candidates in the same order as bin by bin, in 5 runs instead of 14.
  constexpr int kRows[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
  constexpr std::size_t kStencilBins = 14;  // the holder's bin and the 13 forward ones
  const double* X = p.x[0].data();
  const double* Y = p.x[1].data();
  const double* Z = p.x[2].data();
  const double* R = p.radius.data();
  // the history of (a, b) as seen from a: the row of a keyed by b's id (or the wall code), else
  // the row of b keyed by a's id, negated in place; the entry takes that row as its pool slot
  // (rows are in pre-sort order: row perm[i] for particle i; a taken row's key is cleared)
  constexpr double kTaken = -std::numeric_limits<double>::infinity();
  double* key = hist_.hKey.data();
  const auto lookup = [&](std::size_t a, int b) {
    if (a < n) {
      const auto h = static_cast<std::size_t>(perm[a]);
      const double want = static_cast<double>(b >= 0 ? p.id[static_cast<std::size_t>(b)] : b);
      for (int e = hist_.hStart[h]; e < hist_.hStart[h + 1]; ++e)
        if (key[e] == want) {
          key[e] = kTaken;
          list_.slot.push_back(e);
          return;
        }
    }
    if (b >= 0 && static_cast<std::size_t>(b) < n) {
      const auto h = static_cast<std::size_t>(perm[static_cast<std::size_t>(b)]);
      for (int e = hist_.hStart[h]; e < hist_.hStart[h + 1]; ++e)
        if (key[e] == static_cast<double>(p.id[a])) {
          key[e] = kTaken;
          for (int k = 0; k < 3; ++k) hist_.hS[3 * static_cast<std::size_t>(e) + k] *= -1.0;
          list_.slot.push_back(e);
          return;
        }
    }
    list_.slot.push_back(-1);
  };
  // the candidates of a row that pass the distance test, in visiting order: filled without a
  // branch per candidate (a store and a count; the test's outcome is hard to predict), then
  // appended to the row and looked up
  int maxBin = 0;
  for (std::size_t b = 0; b + 1 < bins_.binStart.size(); ++b)
    maxBin = std::max(maxBin, bins_.binStart[b + 1] - bins_.binStart[b]);
  const auto candMax = kStencilBins * static_cast<std::size_t>(maxBin) + 1;
  ensure(candidates_, candMax);
  candidates_.resize(candMax);
  int* const cand = candidates_.data();
  const int* const items = bins_.binItems.data();
  const int nInt = static_cast<int>(n);
  int ba = 0;  // the bin of item q: the run of binItems it lies in
  for (std::size_t q = 0; q < nAll; ++q) {
    while (bins_.binStart[static_cast<std::size_t>(ba) + 1] <= static_cast<int>(q)) ++ba;
    list_.rowStart[q] = static_cast<int>(list_.nbr.size());
    const auto a = static_cast<std::size_t>(items[q]);
    const bool ownA = a < n;
    const int bx = ba % bins_.nbx[0], by = (ba / bins_.nbx[0]) % bins_.nbx[1], bz = ba / sz;
    // the holder's values and the arrays' addresses as copies in the closure, the count in a
    // local: nothing the loop stores can alias them
    int m = 0;
    const auto visit = [&m, cand, items, X, Y, Z, R, skin, nInt, ownA, xa = X[a], ya = Y[a],
                        za = Z[a], ra = R[a]](int from, int to) {
      int k = m;
      for (int t = from; t < to; ++t) {
        const int j = items[t];
        const auto u = static_cast<std::size_t>(j);
        const double ex = xa - X[u], ey = ya - Y[u], ez = za - Z[u];
        const double cut = ra + R[u] + skin;
        cand[k] = j;  // kept if within reach (ghost holders: owned partners only)
        k += static_cast<int>(ex * ex + ey * ey + ez * ez < cut * cut) &
             static_cast<int>(ownA || j < nInt);
      }
      m = k;
    };
    const int nbx = bins_.nbx[0], xlo = std::max(bx - 1, 0), xhi = std::min(bx + 1, nbx - 1);
    visit(static_cast<int>(q) + 1,
          bins_.binStart[static_cast<std::size_t>(ba) + (bx + 1 < nbx ? 2 : 1)]);
    for (const auto& row : kRows) {
      const int cy = by + row[0], cz = bz + row[1];
      if (cy < 0 || cy >= bins_.nbx[1] || cz >= bins_.nbx[2]) continue;
      const int b = cy * sy + cz * sz;
      visit(bins_.binStart[static_cast<std::size_t>(b + xlo)],
            bins_.binStart[static_cast<std::size_t>(b + xhi) + 1]);
    }
    ensureRows(list_.nbr, list_.nbr.size() + static_cast<std::size_t>(m) + 8, q, nAll);
    ensureRows(list_.slot, list_.slot.size() + static_cast<std::size_t>(m) + 8, q, nAll);
    for (int k = 0; k < m; ++k) {
      list_.nbr.push_back(cand[k]);
      lookup(a, cand[k]);
    }
    if (!ownA) continue;
    for (int d = 0; d < 3; ++d)
      for (int s = 0; s < 2; ++s) {
        if (!wallOn[d][static_cast<std::size_t>(s)]) continue;
        const double dist =
            s == 0 ? p.x[d][a] - bins_.origin[d] : bins_.origin[d] + bins_.L[d] - p.x[d][a];
        if (dist < R[a] + skin) {
          const int code = -1 - (2 * d + s);
          list_.nbr.push_back(code);
          lookup(a, code);
        }
      }
  }
  list_.rowStart[nAll] = static_cast<int>(list_.nbr.size());
  trimRows(list_.nbr, kSortBufferInts * n);  // sortByBin's buffer
  trimRows(list_.slot);
  // the inner list: none until the next force pass prunes this one
  ensure(list_.keep, nAll);
  list_.keep.resize(nAll);
  innerValid_ = false;
  // rows no entry took are free slots
  hist_.freeSlots.clear();
  for (std::size_t e = 0; e < hist_.slots(); ++e)
    if (key[e] != kTaken) hist_.freeSlot(static_cast<int>(e));
}

}  // namespace coloc::dem

namespace coloc::dem::detail {

void NeighbourSearch::keepPositions(const ParticleStore& p) {
  // x0 in the keys' array (history.hpp), which the list build has read for the last time
  const std::size_t n = p.nOwned;
  ensure(hist_.hKey, 3 * n);
  hist_.hKey.resize(3 * n);
  for (int d = 0; d < 3; ++d)
    std::copy_n(p.x[d].begin(), n, hist_.hKey.begin() + static_cast<std::ptrdiff_t>(d * n));
}

void NeighbourSearch::moved(double d) {
  // A drift x += dt v moves a particle by dt |v| up to the rounding of the sum (an ulp of the
  // coordinate), and a ghost's copy (x + a box length) by its own rounding: both covered by a
  // relative 2^-40 of d and of the largest coordinate a local particle can have. The test's own
  // rounding (a few ulps of the distances) by the 0.999.
  double xMax = 0;
  for (int c = 0; c < 3; ++c)
    xMax = std::max(xMax, std::abs(bins_.origin[c]) + 2 * bins_.L[c] + 4 * bins_.bs[c]);
  constexpr double kRel = 0x1p-40;
  moved_ += d * (1 + kRel) + kRel * xMax;
  if (!(2 * moved_ < 0.999 * margin_)) innerValid_ = false;
}

double NeighbourSearch::maxDisplacement2(const ParticleStore& p) const {
  double m2 = 0;
  const std::size_t n = p.nOwned;
  // on the vector units: a max-reduction (exact in any order; NaN and inf become the largest
  // double first, so a lost particle forces the rebuild)
  const double *X = p.x[0].data(), *Y = p.x[1].data(), *Z = p.x[2].data();
  const double *X0 = hist_.x0(0, n), *Y0 = hist_.x0(1, n), *Z0 = hist_.x0(2, n);
  constexpr double kBig = std::numeric_limits<double>::max();
#pragma omp simd reduction(max : m2)
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = X[i] - X0[i], dy = Y[i] - Y0[i], dz = Z[i] - Z0[i];
    const double d2 = dx * dx + dy * dy + dz * dz;
    const double c = d2 <= kBig ? d2 : kBig;
    m2 = m2 > c ? m2 : c;
  }
  return m2;
}

}  // namespace coloc::dem::detail
