// coloc/partition/field.hpp — structured arrays with ghost layers on a block of the
// decomposition, and typed index ranges (owned / with ghosts) to loop over them.
//
// Local indices: owned cells are 0..n-1 along each axis, ghosts -g..-1 and n..n+g-1. Storage is
// x-fastest, the layout hypre's SetBoxValues and HDF5 ([nz][ny][nx]) take directly.
// A staggered axis (face-centred component) has one more layer: local face i is the low face of
// local cell i, faces 0..n-1 are owned, face n is the high face of the block (owned only at a
// non-periodic high box face, otherwise it is the neighbour's face 0 and comes as a ghost).
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "coloc/partition/decomposition.hpp"

namespace coloc {

/// A box of local indices [lo, hi) along each axis.
struct IndexBox {
  Int3 lo{0, 0, 0}, hi{0, 0, 0};
  long long volume() const {
    long long v = 1;
    for (int d = 0; d < 3; ++d) v *= (hi[d] > lo[d] ? hi[d] - lo[d] : 0);
    return v;
  }
  bool contains(int i, int j, int k) const {
    return i >= lo[0] && i < hi[0] && j >= lo[1] && j < hi[1] && k >= lo[2] && k < hi[2];
  }
  bool empty() const { return volume() == 0; }
};

/// Visit every (i, j, k) of a box, x fastest.
template <class F>
inline void forEach(const IndexBox& b, F&& f) {
  for (int k = b.lo[2]; k < b.hi[2]; ++k)
    for (int j = b.lo[1]; j < b.hi[1]; ++j)
      for (int i = b.lo[0]; i < b.hi[0]; ++i) f(i, j, k);
}

/// Memory layout of a field on one block: owned extent, ghost width, staggering.
struct FieldLayout {
  Int3 n{1, 1, 1};        // owned cells of the block
  int ghost = 1;          // ghost layers on every side
  Int3 stagger{0, 0, 0};  // 1 along the axis of a face component
  Int3 extent() const {
    return {n[0] + 2 * ghost + stagger[0], n[1] + 2 * ghost + stagger[1],
            n[2] + 2 * ghost + stagger[2]};
  }
  /// Every allocated index (owned and ghosts).
  IndexBox allocated() const {
    return {{-ghost, -ghost, -ghost},
            {n[0] + ghost + stagger[0], n[1] + ghost + stagger[1], n[2] + ghost + stagger[2]}};
  }
  /// Owned indices [0, n) (the top face of a staggered axis is added by faceOwned()).
  IndexBox interior() const { return {{0, 0, 0}, n}; }
  std::size_t size() const {
    const auto e = extent();
    return static_cast<std::size_t>(e[0]) * e[1] * e[2];
  }
  bool operator==(const FieldLayout&) const = default;
};

template <class T>
class Field3 {
 public:
  Field3() = default;
  explicit Field3(const FieldLayout& layout, T init = T{})
      : layout_(layout), data_(layout.size(), init) {
    const auto e = layout.extent();
    sy_ = e[0];
    sz_ = static_cast<std::ptrdiff_t>(e[0]) * e[1];
    offset_ = layout.ghost + layout.ghost * sy_ + layout.ghost * sz_;
  }
  const FieldLayout& layout() const { return layout_; }
  std::ptrdiff_t index(int i, int j, int k) const { return offset_ + i + j * sy_ + k * sz_; }
  T& operator()(int i, int j, int k) { return data_[static_cast<std::size_t>(index(i, j, k))]; }
  const T& operator()(int i, int j, int k) const {
    return data_[static_cast<std::size_t>(index(i, j, k))];
  }
  /// Strides in elements along y and z (x is 1).
  std::ptrdiff_t strideY() const { return sy_; }
  std::ptrdiff_t strideZ() const { return sz_; }
  /// Stride in elements along axis a (0: x, 1: y, 2: z).
  std::ptrdiff_t stride(int a) const { return a == 0 ? 1 : a == 1 ? sy_ : sz_; }
  std::span<T> data() { return data_; }
  std::span<const T> data() const { return data_; }
  void fill(T v) { std::fill(data_.begin(), data_.end(), v); }
  IndexBox allocated() const { return layout_.allocated(); }
  IndexBox interior() const { return layout_.interior(); }

 private:
  FieldLayout layout_;
  std::vector<T> data_;
  std::ptrdiff_t sy_ = 0, sz_ = 0, offset_ = 0;
};

using CellField = Field3<double>;

/// Layout of a cell-centred field on this rank's block.
inline FieldLayout cellLayout(const Decomposition& dec, int ghost) {
  return {dec.cells(), ghost, {0, 0, 0}};
}
/// Layout of face component `d` on this rank's block.
inline FieldLayout faceLayout(const Decomposition& dec, int d, int ghost) {
  FieldLayout l{dec.cells(), ghost, {0, 0, 0}};
  l.stagger[d] = 1;
  return l;
}
/// Faces of component `d` this rank owns: [0, n) plus face n at a non-periodic high box face.
inline IndexBox faceOwned(const Decomposition& dec, int d) {
  IndexBox b{{0, 0, 0}, dec.cells()};
  if (dec.atHighBoundary(d)) b.hi[d] += 1;
  return b;
}

/// Staggered velocity-like field: one Field3 per component.
struct FaceField {
  std::array<Field3<double>, 3> c;
  FaceField() = default;
  FaceField(const Decomposition& dec, int ghost)
      : c{Field3<double>(faceLayout(dec, 0, ghost)), Field3<double>(faceLayout(dec, 1, ghost)),
          Field3<double>(faceLayout(dec, 2, ghost))} {}
  Field3<double>& operator[](int d) { return c[static_cast<std::size_t>(d)]; }
  const Field3<double>& operator[](int d) const { return c[static_cast<std::size_t>(d)]; }
};

}  // namespace coloc
