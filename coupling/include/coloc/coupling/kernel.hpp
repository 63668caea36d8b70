// coloc/coupling/kernel.hpp — deposition and interpolation kernels between particles and cells.
//
// A stencil lists, for each particle, the cells it talks to and their weights (summing to 1):
//   centroid  (PCM): the cell containing the particle centre, weight 1;
//   trilinear (cloud-in-cell): the 8 cells whose centres surround the particle centre, with
//             tensor-product linear weights.
// Deposition adds w * q_i to each stencil cell; interpolation reads sum_c w * f_c. The same
// stencil is used for both within a coupling step, so the two are adjoint:
//   sum_c f_c * deposit(q)_c == sum_i q_i * interpolate(f)_i,
// which is what makes the drag exchange momentum-conserving to round-off.
// Stencil cells may be ghost cells: deposits there are carried to their owner by the reverse halo
// sum (Fold::Mirror at walls), and interpolation reads ghosts filled by the halo gather and by
// fillWallGhostsByMirror() at walls, the adjoint of that fold.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"
#include "coloc/partition/halo.hpp"

namespace coloc::coupling {

enum class KernelKind { Centroid, Trilinear };
KernelKind kernelFromName(const std::string& name);

class Stencils {
 public:
  /// Computes the stencils of n particles at (x, y, z) for fields of `layout` on this block.
  /// Returns the index of the first particle whose stencil reaches beyond the first ghost layer
  /// (or -1); such a particle is clamped, and the caller raises the error.
  long long compute(KernelKind kind, const Decomposition& dec, const FieldLayout& layout,
                    std::span<const double> x, std::span<const double> y, std::span<const double> z,
                    std::size_t n);
  int width() const { return width_; }
  /// Trilinear: the fractional offset (0..1) of particle p from its first cell's centre along
  /// axis d (0 for the centroid kernel).
  double fraction(int d, std::size_t p) const { return width_ == 1 ? 0.0 : frac_[d][p]; }
  std::size_t count() const { return n_; }
  /// The first cell of particle p's stencil (linear index into Field3::data()) and the strides
  /// of the field layout the stencils were computed for.
  std::int32_t firstCell(std::size_t p) const { return base_[p]; }
  std::int32_t strideY() const { return sy_; }
  std::int32_t strideZ() const { return sz_; }
  /// Calls f(cell, weight) for the cells of particle p: cell is a linear index into
  /// Field3::data(), the weights sum to 1. A stencil is stored compactly (28 bytes a particle for
  /// the trilinear kernel, 4 for the centroid): the first cell (32-bit: a block holds < 2^31
  /// cells) and the fractional offsets, from which the 8 tensor-product weights are formed.
  template <class F>
  void forEachCell(std::size_t p, F&& f) const {
    const std::int32_t c0 = base_[p];
    if (width_ == 1) {
      f(c0, 1.0);
      return;
    }
    const double t[3] = {frac_[0][p], frac_[1][p], frac_[2][p]};
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di)
          f(c0 + di + dj * sy_ + dk * sz_,
            (di ? t[0] : 1.0 - t[0]) * (dj ? t[1] : 1.0 - t[1]) * (dk ? t[2] : 1.0 - t[2]));
  }
  /// Bytes held (capacities).
  std::size_t memoryBytes() const {
    return base_.capacity() * sizeof(std::int32_t) +
           (frac_[0].capacity() + frac_[1].capacity() + frac_[2].capacity()) * sizeof(double);
  }

 private:
  int width_ = 1;
  std::size_t n_ = 0;
  std::int32_t sy_ = 0, sz_ = 0;
  std::vector<std::int32_t> base_;
  std::array<std::vector<double>, 3> frac_;
};

/// f_c += sum_i w_ic * scale * q_i over the stencils (q empty: q_i = 1).
void deposit(const Stencils& s, std::span<const double> q, double scale, CellField& f);
/// f_c += sum_i w_ic * scale * (a_i b_i): a deposit of a product without storing it.
void depositProduct(const Stencils& s, std::span<const double> a, std::span<const double> b,
                    double scale, CellField& f);
/// out_i = sum_c w_ic f_c. Trilinear: the cells in 4 pairs of x-neighbours, two doubles at a time,
/// summed (w0 f0 + w2 f2 + w4 f4 + w6 f6) + (w1 f1 + w3 f3 + w5 f5 + w7 f7) (m = di + 2 dj + 4 dk);
/// the deposits add w * q to each cell as forEachCell() lists them.
void interpolate(const Stencils& s, const CellField& f, std::span<double> out);

/// The fused kernels of a coupling step: one pass over the particles, each particle's stencil
/// weights formed once and used for every field. Each field's values are those of the one-field
/// kernels above, bit for bit (same weights, same order of the additions into each value).
/// With fewer particles than half the cells, interpolate() makes one pass a field instead (the
/// stencils share few cells; measured faster). Cell-interleaved copies of the fields (one cache
/// line a stencil cell) were measured too: no faster here, the deposit 1.7x slower
/// (docs/benchmarks.md, "Coupling arithmetic").
inline constexpr std::size_t kMaxFusedFields = 8;
/// out[k]_i = sum_c w_ic f[k]_c for every field k (at most kMaxFusedFields; out[k] holds
/// s.count() values).
void interpolate(const Stencils& s, std::span<const CellField* const> f,
                 std::span<double* const> out);
/// The same for particles first .. first + count - 1 only: out[k][j] = value of particle
/// first + j (each value as in the whole pass).
void interpolate(const Stencils& s, std::span<const CellField* const> f,
                 std::span<double* const> out, std::size_t first, std::size_t count);
/// One deposit of a fused pass: f_c += sum_i w_ic * scale * q_i with q_i = a_i b_i (b given),
/// a_i (b null) or 1 (a and b null), as deposit() and depositProduct() form it.
struct DepositTerm {
  const double* a = nullptr;
  const double* b = nullptr;
  double scale = 1.0;
  CellField* f = nullptr;
};
/// Every term's deposit in one pass (at most kMaxFusedFields terms, distinct fields).
void deposit(const Stencils& s, std::span<const DepositTerm> terms);
/// One pass of a conservative, self-adjoint smoothing filter on the owned cells:
///   f_c <- f_c + alpha * sum_{6 neighbours} (f_nb - f_c),  alpha = 1/8 (stable below 1/6),
/// with the neighbours' values from a halo gather and zero flux through walls (mirror ghosts).
/// Applied to the deposited fields and, before interpolation, to the sampled fields, it keeps
/// deposit and interpolation adjoint (the drag exchange stays exactly conservative).
/// `scratch` must have f's layout.
void smooth(const Decomposition& dec, HaloPlan& halo, CellField& f, CellField& scratch);

/// Fill the ghost layers beyond non-periodic box faces with the mirror image of the owned layers
/// (ghost -1-m <- owned m): the adjoint of the Fold::Mirror reverse halo sum.
void fillWallGhostsByMirror(const Decomposition& dec, CellField& f);

}  // namespace coloc::coupling
