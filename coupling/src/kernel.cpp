#include "coloc/coupling/kernel.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include "coloc/core/error.hpp"

namespace coloc::coupling {

KernelKind kernelFromName(const std::string& name) {
  if (name == "centroid") return KernelKind::Centroid;
  if (name == "trilinear") return KernelKind::Trilinear;
  throw ConfigError("coupling.kernel", "unknown kernel '" + name + "'");
}

long long Stencils::compute(KernelKind kind, const Decomposition& dec, const FieldLayout& layout,
                            std::span<const double> x, std::span<const double> y,
                            std::span<const double> z, std::size_t n) {
  width_ = kind == KernelKind::Centroid ? 1 : 8;
  n_ = n;
  if (base_.size() < n) base_.resize(n + n / 4);
  if (width_ > 1 && frac_[0].size() < n)
    for (auto& f : frac_) f.resize(n + n / 4);
  const auto lo = dec.blockLo();
  const auto& g = dec.grid();
  const double inv[3] = {1.0 / g.spacing(0), 1.0 / g.spacing(1), 1.0 / g.spacing(2)};
  // Stencils reach at most one ghost layer (the layer the solvers keep filled for the coupling).
  IndexBox box = layout.allocated();
  for (int d = 0; d < 3; ++d) {
    box.lo[d] = std::max(box.lo[d], -1);
    box.hi[d] = std::min(box.hi[d], layout.n[d] + 1);
  }
  const auto e = layout.extent();
  if (layout.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw Error(
        "coupling: a block of more than 2^31 cells (with ghosts) per rank is not supported; "
        "use more ranks");
  sy_ = e[0];
  sz_ = static_cast<std::int32_t>(e[0]) * e[1];
  const std::int32_t off = layout.ghost + layout.ghost * sy_ + layout.ghost * sz_;
  long long bad = -1;
  for (std::size_t p = 0; p < n; ++p) {
    const double s[3] = {(x[p] - lo[0]) * inv[0], (y[p] - lo[1]) * inv[1], (z[p] - lo[2]) * inv[2]};
    int i[3];
    if (kind == KernelKind::Centroid) {
      for (int d = 0; d < 3; ++d) {
        i[d] = static_cast<int>(std::floor(s[d]));
        // A centre exactly on the top face of the box belongs to the last cell.
        if (i[d] == layout.n[d] && dec.atHighBoundary(d)) i[d] = layout.n[d] - 1;
        if (i[d] < box.lo[d] || i[d] >= box.hi[d]) bad = bad < 0 ? static_cast<long long>(p) : bad;
        i[d] = std::clamp(i[d], box.lo[d], box.hi[d] - 1);
      }
    } else {
      for (int d = 0; d < 3; ++d) {
        const double u = s[d] - 0.5;
        i[d] = static_cast<int>(std::floor(u));
        frac_[d][p] = u - i[d];
        if (i[d] < box.lo[d] || i[d] + 1 >= box.hi[d]) {
          bad = bad < 0 ? static_cast<long long>(p) : bad;
          i[d] = std::clamp(i[d], box.lo[d], box.hi[d] - 2);
        }
      }
    }
    base_[p] = off + i[0] + i[1] * sy_ + i[2] * sz_;
  }
  return bad;
}

void deposit(const Stencils& s, std::span<const double> q, double scale, CellField& f) {
  double* data = f.data().data();
  for (std::size_t p = 0; p < s.count(); ++p) {
    const double v = scale * (q.empty() ? 1.0 : q[p]);
    s.forEachCell(p, [&](std::int32_t c, double w) { data[c] += w * v; });
  }
}

void depositProduct(const Stencils& s, std::span<const double> a, std::span<const double> b,
                    double scale, CellField& f) {
  double* data = f.data().data();
  for (std::size_t p = 0; p < s.count(); ++p) {
    const double v = scale * (a[p] * b[p]);
    s.forEachCell(p, [&](std::int32_t c, double w) { data[c] += w * v; });
  }
}

namespace {

// Two doubles, lane by lane (GCC/Clang vector extension; SSE2 in the portable x86-64 build).
using D2 = double __attribute__((vector_size(16)));
inline D2 load2(const double* a) {
  D2 v;
  std::memcpy(&v, a, sizeof v);
  return v;
}
inline void store2(double* a, D2 v) {
  std::memcpy(a, &v, sizeof v);
}

// The 8 cells of a trilinear stencil as 4 pairs of x-neighbours (cells c and c + 1, adjacent in
// memory) and their weights, formed once per particle. Weight of cell (di, dj, dk):
// (wx[di] * wy[dj]) * wz[dk], the product forEachCell() forms, in its order.
struct Pairs4 {
  std::int32_t c[4];
  D2 w[4];
};

inline void pairs(const Stencils& s, std::size_t p, std::int32_t sy, std::int32_t sz, Pairs4& k) {
  const double t0 = s.fraction(0, p), t1 = s.fraction(1, p), t2 = s.fraction(2, p);
  const D2 wx = {1.0 - t0, t0};
  const double wy[2] = {1.0 - t1, t1}, wz[2] = {1.0 - t2, t2};
  const std::int32_t c0 = s.firstCell(p);
  int m = 0;
  for (int dk = 0; dk < 2; ++dk)
    for (int dj = 0; dj < 2; ++dj, ++m) {
      k.c[m] = c0 + dj * sy + dk * sz;
      k.w[m] = wx * wy[dj] * wz[dk];
    }
}

template <std::size_t N>
void interpolateN(const Stencils& s, std::span<const CellField* const> f,
                  std::span<double* const> out, std::size_t first, std::size_t count) {
  // Particles first .. first + count - 1, particle p's values to o[k][p - first].
  const double* data[N];
  double* o[N];
  for (std::size_t k = 0; k < N; ++k) data[k] = f[k]->data().data(), o[k] = out[k];
  const std::size_t n = first + count;
  if (s.width() == 1) {
    for (std::size_t p = first; p < n; ++p) {
      const std::int32_t c = s.firstCell(p);
      for (std::size_t k = 0; k < N; ++k) o[k][p - first] = 0.0 + 1.0 * data[k][c];
    }
    return;
  }
  const std::int32_t sy = s.strideY(), sz = s.strideZ();
  Pairs4 st;
  for (std::size_t p = first; p < n; ++p) {
    // Per field: the 4 x-pairs summed lane by lane (cells di = 0 and di = 1 apart), then the two
    // lanes: (w0 f0 + w2 f2 + w4 f4 + w6 f6) + (w1 f1 + w3 f3 + w5 f5 + w7 f7), m = di + 2 dj +
    // 4 dk. Each value depends on the particle's own stencil only.
    pairs(s, p, sy, sz, st);
    D2 acc[N];
    for (std::size_t k = 0; k < N; ++k) acc[k] = st.w[0] * load2(data[k] + st.c[0]);
    for (int m = 1; m < 4; ++m)
      for (std::size_t k = 0; k < N; ++k) acc[k] += st.w[m] * load2(data[k] + st.c[m]);
    for (std::size_t k = 0; k < N; ++k) o[k][p - first] = acc[k][0] + acc[k][1];
  }
}

template <std::size_t N>
void depositN(const Stencils& s, std::span<const DepositTerm> terms, std::size_t first,
              std::size_t count) {
  double* data[N];
  const double* a[N];
  const double* b[N];
  double scale[N];
  for (std::size_t k = 0; k < N; ++k) {
    data[k] = terms[k].f->data().data();
    a[k] = terms[k].a, b[k] = terms[k].b, scale[k] = terms[k].scale;
  }
  const std::size_t n = first + count;
  const std::int32_t sy = s.strideY(), sz = s.strideZ();
  Pairs4 st;
  for (std::size_t p = first; p < n; ++p) {
    double v[N];
    for (std::size_t k = 0; k < N; ++k)
      v[k] = b[k] ? scale[k] * (a[k][p] * b[k][p]) : scale[k] * (a[k] ? a[k][p] : 1.0);
    if (s.width() == 1) {
      const std::int32_t c = s.firstCell(p);
      for (std::size_t k = 0; k < N; ++k) data[k][c] += 1.0 * v[k];
      continue;
    }
    // data[c] += w v cell by cell, two x-neighbours at once: the same additions as one cell at a
    // time (a particle's 8 cells are distinct).
    pairs(s, p, sy, sz, st);
    for (int m = 0; m < 4; ++m)
      for (std::size_t k = 0; k < N; ++k) {
        double* c = data[k] + st.c[m];
        store2(c, load2(c) + st.w[m] * v[k]);
      }
  }
}

template <std::size_t... I>
void interpolateAny(const Stencils& s, std::span<const CellField* const> f,
                    std::span<double* const> out, std::size_t first, std::size_t count,
                    std::index_sequence<I...>) {
  ((f.size() == I + 1 ? interpolateN<I + 1>(s, f, out, first, count) : void()), ...);
}

template <std::size_t... I>
void depositAny(const Stencils& s, std::span<const DepositTerm> terms, std::size_t first,
                std::size_t count, std::index_sequence<I...>) {
  ((terms.size() == I + 1 ? depositN<I + 1>(s, terms, first, count) : void()), ...);
}

}  // namespace

void interpolate(const Stencils& s, const CellField& f, std::span<double> out) {
  // The fused kernel on one field: the same sums (in the same order) as a fused pass.
  const CellField* fs[1] = {&f};
  double* o[1] = {out.data()};
  interpolateN<1>(s, fs, o, 0, s.count());
}

void interpolate(const Stencils& s, std::span<const CellField* const> f,
                 std::span<double* const> out) {
  interpolate(s, f, out, 0, s.count());
}

void interpolate(const Stencils& s, std::span<const CellField* const> f,
                 std::span<double* const> out, std::size_t first, std::size_t count) {
  if (f.size() != out.size() || f.size() > kMaxFusedFields || first + count > s.count())
    throw Error(fmt::format(
        "coupling: interpolate: {} fields, {} outputs (at most {}), particles {} + {} of {}",
        f.size(), out.size(), kMaxFusedFields, first, count, s.count()));
  // Fewer particles than half the cells: one pass a field. The stencils then share few cells,
  // and the 4 rows of cells one field's stencils walk stream better than 4 N rows at once
  // (bench_coupling BM_Sample7: 1e5 particles in 64^3 cells, 2x faster than one fused pass).
  if (2 * s.count() < f[0]->data().size()) {
    for (std::size_t k = 0; k < f.size(); ++k)
      interpolateN<1>(s, f.subspan(k, 1), out.subspan(k, 1), first, count);
    return;
  }
  interpolateAny(s, f, out, first, count, std::make_index_sequence<kMaxFusedFields>());
}

void deposit(const Stencils& s, std::span<const DepositTerm> terms) {
  if (terms.size() > kMaxFusedFields)
    throw Error(
        fmt::format("coupling: deposit: {} terms (at most {})", terms.size(), kMaxFusedFields));
  depositAny(s, terms, 0, s.count(), std::make_index_sequence<kMaxFusedFields>());
}

void smooth(const Decomposition& dec, HaloPlan& halo, CellField& f, CellField& scratch) {
  constexpr double alpha = 1.0 / 8.0;
  halo.gather(f);
  fillWallGhostsByMirror(dec, f);
  const std::ptrdiff_t sy = f.strideY(), sz = f.strideZ();
  const double* in = f.data().data();
  double* out = scratch.data().data();
  forEach(f.interior(), [&](int i, int j, int k) {
    const std::ptrdiff_t c = f.index(i, j, k);
    const double v = in[c];
    out[c] = v + alpha * (in[c - 1] + in[c + 1] + in[c - sy] + in[c + sy] + in[c - sz] +
                          in[c + sz] - 6.0 * v);
  });
  forEach(f.interior(), [&](int i, int j, int k) { f(i, j, k) = scratch(i, j, k); });
}

void fillWallGhostsByMirror(const Decomposition& dec, CellField& f) {
  const auto& l = f.layout();
  const IndexBox all = l.allocated();
  // Axis by axis over the full transverse extent, so edges and corners mirror twice, exactly as
  // the fold of the reverse sum adds them.
  for (int d = 0; d < 3; ++d) {
    for (int side = 0; side < 2; ++side) {
      if (side == 0 ? !dec.atLowBoundary(d) : !dec.atHighBoundary(d)) continue;
      for (int m = 0; m < l.ghost; ++m) {
        const int ghost = side == 0 ? -1 - m : l.n[d] + m;
        const int owned = side == 0 ? std::min(m, l.n[d] - 1) : std::max(l.n[d] - 1 - m, 0);
        IndexBox layer = all;
        layer.lo[d] = ghost;
        layer.hi[d] = ghost + 1;
        forEach(layer, [&](int i, int j, int k) {
          int src[3] = {i, j, k};
          src[d] = owned;
          f(i, j, k) = f(src[0], src[1], src[2]);
        });
      }
    }
  }
}

}  // namespace coloc::coupling
