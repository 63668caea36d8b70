// dem/src/rows.hpp — particle rows packed and unpacked generically over the field table
// (coloc/dem/fields.hpp): contiguous rows of doubles, independent of how they are sent.
#pragma once

#include <cstddef>
#include <span>

#include "coloc/dem/dem.hpp"

namespace coloc::dem::detail {

/// Particle i's fields of `op` -> out[0, rowWidth). `shift` (3 values, or nullptr) is added to
/// the position components (the ghost operations pass the periodic shift of their swap).
void packRow(const ParticleStore& p, unsigned op, std::size_t i, const double* shift, double* out);
/// Particles idx[0..m) -> m consecutive rows at out.
void packRows(const ParticleStore& p, unsigned op, std::span<const int> idx, const double* shift,
              double* out);
/// One row -> particle i. `fresh`: a new row, whose fields outside `op` are set to zero.
void unpackRow(ParticleStore& p, unsigned op, const double* in, std::size_t i, bool fresh);
/// m consecutive rows -> particles first .. first + m - 1.
void unpackRows(ParticleStore& p, unsigned op, const double* in, std::size_t m, std::size_t first,
                bool fresh);

/// Every column of every field sized to n rows (grow-only capacity, see buffers.hpp).
void resizeAll(ParticleStore& p, std::size_t n);
/// Row `from` copied to row `to` in every column.
void copyRow(ParticleStore& p, std::size_t from, std::size_t to);
/// Bytes held by the columns (capacities).
std::size_t columnBytes(const ParticleStore& p);

/// f(std::vector<T>&) for every column of every field (T = std::int64_t, int or double).
template <class F>
void forEachColumn(ParticleStore& p, F&& f) {
  forEachField(p, [&](const FieldInfo& fi, auto* cols) {
    for (int k = 0; k < fi.components; ++k) f(cols[k]);
  });
}

}  // namespace coloc::dem::detail
