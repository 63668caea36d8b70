// dem/src/history.cpp — the contact-history pool: rows per owned particle at a rebuild (packing),
// row compaction, the pool compacted after a restore.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "impl.hpp"
#include "rows.hpp"

namespace coloc::dem {

using namespace detail;

int HistoryPool::newSlot() {
  std::size_t s;
  if (!freeSlots.empty()) {
    s = static_cast<std::size_t>(freeSlots.back());
    freeSlots.pop_back();
  } else {
    s = slots();
    ensure(hS, 3 * s + 3);
    hS.resize(3 * s + 3);
  }
  hS[3 * s] = hS[3 * s + 1] = hS[3 * s + 2] = 0;
  return static_cast<int>(s);
}

void HistoryPool::freeSlot(int s) {
  ensure(freeSlots, freeSlots.size() + 1);
  freeSlots.push_back(s);
}

void HistoryPool::keepRows(std::size_t w, int h0, int h1, int& hw) {
  hStart[w] = hw;
  for (int e = h0; e < h1; ++e, ++hw) {
    hKey[static_cast<std::size_t>(hw)] = hKey[static_cast<std::size_t>(e)];
    for (int k = 0; k < 3; ++k)
      hS[3 * static_cast<std::size_t>(hw) + static_cast<std::size_t>(k)] =
          hS[3 * static_cast<std::size_t>(e) + static_cast<std::size_t>(k)];
  }
}

void HistoryPool::truncate(std::size_t rows, int hw) {
  hStart.resize(rows + 1);
  hStart[rows] = hw;
  hKey.resize(static_cast<std::size_t>(hw));
  hS.resize(3 * static_cast<std::size_t>(hw));
}

void HistoryPool::compact(std::vector<int>& slot) {
  std::vector<double> v;
  v.reserve(3 * (slots() - freeSlots.size()) + 16);
  for (auto& s : slot)
    if (s >= 0) {
      v.insert(v.end(), hS.begin() + 3 * s, hS.begin() + 3 * s + 3);
      s = static_cast<int>(v.size() / 3 - 1);
    }
  hS.swap(v);
  std::vector<int>().swap(freeSlots);
}

void detail::keepRow(ParticleStore& p, HistoryPool& hist, std::size_t i, std::size_t w, int h0,
                     int h1, int& hw) {
  if (w != i) copyRow(p, i, w);
  hist.keepRows(w, h0, h1, hw);
}

void DemSolver::Impl::keepRow(std::size_t i, std::size_t w, int h0, int h1, int& hw) {
  detail::keepRow(p, search.mutableHistory(), i, w, h0, h1, hw);
}

void NeighbourSearch::packHistory(const ParticleStore& p, const Decomposition& dec, int nRanks,
                                  const Lender& lend) {
  // The history pool becomes rows per owned particle (the format migration carries and the list
  // build reads), keyed by the partner's global id (walls: -1..-6), shear as seen from the row's
  // particle. An owned-ghost pair has one row, under its owned particle; an owned-owned pair one
  // under its holder, and a second one under the partner when the two are bound for different
  // ranks or only one of them wraps across a periodic face (the pair is then computed by each
  // side for its own particle, with its own copy, as every owned-ghost pair). The live slots are
  // gathered into row order in a buffer lent by the owner (the packed bodies, dead from the start
  // of a rebuild to the next force pass: loads at independent addresses, where a walk along the
  // permutation's cycles in place was a chain of dependent ones), then copied back.
  const std::size_t n = p.nOwned, nAll = p.size();
  // scratch: the destination code of every particle, then the row cursors
  ensure(scratch_, 2 * n);
  scratch_.resize(2 * n);
  int* const code = scratch_.data();
  int* const cur = code + n;
  for (std::size_t i = 0; i < n; ++i) {  // destination rank and periodic wrap of every particle
    double x[3];
    int wrap = 0;
    for (int d = 0, w = 1; d < 3; ++d, w *= 3) {
      x[d] = p.x[d][i];
      if (bins_.periodic[d]) {
        if (x[d] < bins_.origin[d]) {
          x[d] += bins_.L[d];
          wrap += w;
        } else if (x[d] >= bins_.origin[d] + bins_.L[d]) {
          x[d] -= bins_.L[d];
          wrap += 2 * w;
        }
      }
    }
    code[i] = (nRanks > 1 ? bins_.ownerRank(dec, x) * 27 : 0) + wrap;
  }
  const auto dup = [&](std::size_t a, int j) {
    return a < n && j >= 0 && static_cast<std::size_t>(j) < n &&
           code[a] != code[static_cast<std::size_t>(j)];
  };
  // pass 1: rows per particle; slots of zero histories are dropped
  ensure(hist_.hStart, n + 1);
  hist_.hStart.assign(n + 1, 0);
  for (std::size_t q = 0; q < nAll; ++q) {
    const auto a = static_cast<std::size_t>(bins_.binItems[q]);
    for (int e = list_.rowStart[q]; e < list_.rowStart[q + 1]; ++e) {
      const int s = list_.slot[static_cast<std::size_t>(e)];
      if (s < 0) continue;
      const double* v = &hist_.hS[3 * static_cast<std::size_t>(s)];
      if (v[0] == 0 && v[1] == 0 && v[2] == 0) {
        list_.slot[static_cast<std::size_t>(e)] = -1;
        continue;
      }
      const int j = list_.nbr[static_cast<std::size_t>(e)];
      ++hist_.hStart[(a < n ? a : static_cast<std::size_t>(j)) + 1];
      if (dup(a, j)) ++hist_.hStart[static_cast<std::size_t>(j) + 1];
    }
  }
  for (std::size_t i = 0; i < n; ++i) hist_.hStart[i + 1] += hist_.hStart[i];
  const auto T = static_cast<std::size_t>(hist_.hStart[n]);
  // pass 2: every live slot's shear to its row (and the second copy), oriented, into the buffer;
  // its key beside it. The keys' array held x0 until now (the rebuild check is done).
  constexpr std::size_t kRec = 3 * sizeof(double);
  unsigned char* const buf = lend(T * kRec);
  std::vector<double>& key = hist_.hKey;
  ensure(key, T);
  key.resize(T);
  const std::int64_t* const id = p.id.data();
  std::copy(hist_.hStart.begin(), hist_.hStart.end() - 1, cur);
  for (std::size_t q = 0; q < nAll; ++q) {
    const auto a = static_cast<std::size_t>(bins_.binItems[q]);
    for (int e = list_.rowStart[q]; e < list_.rowStart[q + 1]; ++e) {
      const int s = list_.slot[static_cast<std::size_t>(e)];
      if (s < 0) continue;
      const int j = list_.nbr[static_cast<std::size_t>(e)];
      const double* v = &hist_.hS[3 * static_cast<std::size_t>(s)];
      double w[3];
      std::size_t pos;
      if (a < n) {
        pos = static_cast<std::size_t>(cur[a]++);
        key[pos] = static_cast<double>(j >= 0 ? id[static_cast<std::size_t>(j)] : j);
        for (int c = 0; c < 3; ++c) w[c] = v[c];
      } else {  // under the owned partner, seen from it
        pos = static_cast<std::size_t>(cur[static_cast<std::size_t>(j)]++);
        key[pos] = static_cast<double>(id[a]);
        for (int c = 0; c < 3; ++c) w[c] = -v[c];
      }
      std::memcpy(buf + pos * kRec, w, kRec);
      if (dup(a, j)) {
        const auto r = static_cast<std::size_t>(cur[static_cast<std::size_t>(j)]++);
        key[r] = static_cast<double>(id[a]);
        for (int c = 0; c < 3; ++c) w[c] = -w[c];
        std::memcpy(buf + r * kRec, w, kRec);
      }
    }
  }
  ensure(hist_.hS, 3 * T);
  hist_.hS.resize(3 * T);
  if (T > 0) std::memcpy(hist_.hS.data(), buf, T * kRec);
  hist_.freeSlots.clear();
}

}  // namespace coloc::dem
