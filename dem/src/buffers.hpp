// dem/src/buffers.hpp — grow-only buffers of the DEM (no allocation in the step loop once the
// largest sizes have been seen) and small shared helpers.
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace coloc::dem::detail {

inline const char* const kAxis[3] = {"x", "y", "z"};

template <class T>
std::size_t cap(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

/// Large buffers (>= 4 MiB) are marked for transparent huge pages (THP in "madvise" mode): the
/// first touch of a multi-million-particle set-up then takes one page fault per 2 MiB instead of
/// per 4 KiB (page faults were a third of a 2M-particle set-up), and the scattered partner reads
/// of the force loop miss the TLB less. Only the 2 MiB-aligned interior is marked; no effect on
/// the contents or the capacity.
template <class T>
void hugePages(std::vector<T>& v) {
  constexpr std::size_t kHuge = std::size_t{2} << 20;
  const std::size_t bytes = v.capacity() * sizeof(T);
  if (bytes < 2 * kHuge) return;
  const auto a = reinterpret_cast<std::uintptr_t>(v.data());
  const std::uintptr_t b = (a + kHuge - 1) & ~(kHuge - 1), e = (a + bytes) & ~(kHuge - 1);
  if (e > b) madvise(reinterpret_cast<void*>(b), e - b, MADV_HUGEPAGE);
}

/// Headroom of the grow-only buffers: 1/kSlack of the size (1/16: ~6 % slack; was 1/8, whose
/// ~12 % was a tenth of the solver's memory; the ghosts and migrants of a step stay well inside
/// either).
inline constexpr std::size_t kSlack = 16;

/// Grow-only capacity with 1/kSlack headroom (instead of the 2x of push_back): the arrays hold
/// at most ~6 % slack, and once the largest size has been seen nothing is allocated again.
template <class T>
void ensure(std::vector<T>& v, std::size_t need) {
  if (v.capacity() < need) {
    v.reserve(need + need / kSlack + 16);
    hugePages(v);
  }
}

/// ensure() for a buffer filled row by row: when it must grow, it grows to the size extrapolated
/// from the rows done so far (+1/kSlack), so a first build of millions of rows reallocates a
/// few times instead of hundreds of times (1/kSlack steps).
template <class T>
void ensureRows(std::vector<T>& v, std::size_t need, std::size_t rowsDone, std::size_t rows) {
  if (v.capacity() >= need) return;
  const std::size_t est = rowsDone > 0 ? static_cast<std::size_t>(static_cast<double>(v.size()) /
                                                                  static_cast<double>(rowsDone) *
                                                                  static_cast<double>(rows))
                                       : 0;
  ensure(v, std::max(need, est));
}

/// After a row-by-row fill: an extrapolated capacity above the size + 1/kSlack (by more than a
/// quarter of that headroom) is trimmed to the size + 1/kSlack (one copy; grow-only otherwise),
/// never below `floor` elements (a buffer lent to another use of that size keeps it).
template <class T>
void trimRows(std::vector<T>& v, std::size_t floor = 0) {
  const std::size_t n = v.size();
  if (v.capacity() > std::max(n + n / kSlack + n / (4 * kSlack) + 64, floor)) {
    std::vector<T> t;
    t.reserve(std::max(n + n / kSlack + 16, floor));
    t.assign(v.begin(), v.end());
    v.swap(t);
    hugePages(v);
  }
}

/// Room that one part lends another while its own contents are dead (the force part's packed
/// bodies from the start of a rebuild to the next force pass, lent to the history packing):
/// lend(bytes) returns at least that many bytes, 64-byte aligned, grown if needed (grow-only).
using Lender = std::function<unsigned char*(std::size_t bytes)>;

}  // namespace coloc::dem::detail
