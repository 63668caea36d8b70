// fv/src/cell_rows.hpp — per-cell work of the fluid step along a row of cells (fixed j, k): the
// pressure equation's matrix and right-hand side away from boundary faces, the rates (CFL,
// largest speed and change), the cell pressure gradient away from boundary faces. Straight loops
// over the row that the compiler vectorises, each cell's arithmetic in the order of the
// cell-by-cell form in step.cpp (so the same bits), the sums and maxima over cells left to the
// caller, in cell order.
#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace coloc::fv {

/// One row of cells: the arrays at its first cell (index 0 is the cell i = 0 of the row).
struct RhsRow {
  const double* eps;     // eps^{n+1}, cells
  const double* epsOld;  // eps^n, cells
  const double* u[3];    // face velocity of axis a: u[a][i] on the low face of cell i
  const double* p;       // pressure (the warm start), or null for a zero guess
  std::ptrdiff_t cellStride[3], faceStride[3];
  double h[3], idt, dt;
};

/// Cells [i0, i1) of the row: rhs = -div(eps u*) - (eps^{n+1} - eps^n) / dt, scale2 = the
/// square of the row's scale term (|flux| sum + |d eps| / dt), sol = the initial guess.
inline void rhsRow(const RhsRow& in, int i0, int i1, double* __restrict rhs,
                   double* __restrict scale2, double* __restrict sol) {
  const double* __restrict e = in.eps;
  const double* __restrict eo = in.epsOld;
  const double* __restrict u0 = in.u[0];
  const double* __restrict u1 = in.u[1];
  const double* __restrict u2 = in.u[2];
  const std::ptrdiff_t s1 = in.cellStride[1], s2 = in.cellStride[2];
  const std::ptrdiff_t q0 = in.faceStride[0], q1 = in.faceStride[1], q2 = in.faceStride[2];
  const double h0 = in.h[0], h1 = in.h[1], h2 = in.h[2], idt = in.idt;
  for (int i = i0; i < i1; ++i) {
    double div = 0, flux = 0;
    {
      const double elo = 0.5 * (e[i - 1] + e[i]), ehi = 0.5 * (e[i] + e[i + 1]);
      const double uh = ehi * u0[i + q0], ul = elo * u0[i];
      div += (uh - ul) / h0;
      flux += (std::fabs(uh) + std::fabs(ul)) / h0;
    }
    {
      const double elo = 0.5 * (e[i - s1] + e[i]), ehi = 0.5 * (e[i] + e[i + s1]);
      const double uh = ehi * u1[i + q1], ul = elo * u1[i];
      div += (uh - ul) / h1;
      flux += (std::fabs(uh) + std::fabs(ul)) / h1;
    }
    {
      const double elo = 0.5 * (e[i - s2] + e[i]), ehi = 0.5 * (e[i] + e[i + s2]);
      const double uh = ehi * u2[i + q2], ul = elo * u2[i];
      div += (uh - ul) / h2;
      flux += (std::fabs(uh) + std::fabs(ul)) / h2;
    }
    const double de = e[i] - eo[i];
    rhs[i] = -div - de * idt;
    const double sc = flux + std::fabs(de) * idt;
    scale2[i] = sc * sc;
  }
  if (in.p) {
    const double* __restrict p = in.p;
    for (int i = i0; i < i1; ++i) sol[i] = p[i] * in.dt;
  } else {
    for (int i = i0; i < i1; ++i) sol[i] = 0.0;
  }
}

/// One row of cells for the matrix: the arrays at its first cell.
struct MatrixRow {
  const double* eps;  // eps, cells
  const double* K;    // drag coefficient K, cells
  std::ptrdiff_t cellStride[3];
  double h[3], dt;
};

/// Cells [i0, i1) of the row: the face weights w = eps_f^2 / ((eps_f + K_f dt) h^2) of the 6
/// faces (x low, x high, y low, ..., z high) into w[f * ws + i], then the 7 coefficients of cell
/// i (the diagonal, the sum of the weights in that order, then -w face by face) into
/// out[7 i ...]. Returns whether a face's K_f is not zero.
inline bool matrixRow(const MatrixRow& in, int i0, int i1, double* __restrict w, std::size_t ws,
                      double* __restrict out) {
  const double* __restrict e = in.eps;
  const double* __restrict K = in.K;
  const double dt = in.dt;
  // K_f != 0 as the bits of |K_f| (NaN included): an integer OR, which vectorises
  std::uint64_t anyK = 0;
  constexpr std::uint64_t kMagnitude = ~(std::uint64_t{1} << 63);
  for (int a = 0; a < 3; ++a) {
    const std::ptrdiff_t s = in.cellStride[a];
    const double h = in.h[a];
    for (int side = 0; side < 2; ++side) {
      const std::ptrdiff_t o = side == 0 ? -s : s;
      double* __restrict wf = w + static_cast<std::size_t>(2 * a + side) * ws;
      for (int i = i0; i < i1; ++i) {
        const double ef = 0.5 * (e[i] + e[i + o]);
        const double kf = 0.5 * (K[i] + K[i + o]);
        anyK |= std::bit_cast<std::uint64_t>(kf) & kMagnitude;
        wf[i] = ef * ef / ((ef + kf * dt) * h * h);
      }
    }
  }
  for (int i = i0; i < i1; ++i) {
    double* row = out + 7 * static_cast<std::size_t>(i);
    double diag = 0;
    for (int f = 0; f < 6; ++f) {
      const double wi = w[static_cast<std::size_t>(f) * ws + static_cast<std::size_t>(i)];
      row[1 + f] = -wi;
      diag += wi;
    }
    row[0] = diag;
  }
  return anyK != 0;
}

/// One row of cells for the rates: the face velocities (and their values before the step) at the
/// low face of its first cell.
struct RatesRow {
  const double* u[3];
  const double* uPrev[3];  // null: no change measured (dt = 0)
  std::ptrdiff_t faceStride[3];
  double h[3];
};

/// Cells [0, n) of the row, into out[f * ws + i]: f = 0 the rate sum_a max(|u_lo|, |u_hi|) / h_a
/// (axis order), 1 the largest |u_lo| over the axes, 2 the largest |u_lo - uPrev_lo| (with
/// uPrev), 3 zero exactly when the cell's 6 face velocities are finite (NaN otherwise).
inline void ratesRow(const RatesRow& in, int n, double* __restrict out, std::size_t ws) {
  double* __restrict rate = out;
  double* __restrict speed = out + ws;
  double* __restrict change = out + 2 * ws;
  double* __restrict finite = out + 3 * ws;
  const double* __restrict u0 = in.u[0];
  const double* __restrict u1 = in.u[1];
  const double* __restrict u2 = in.u[2];
  const std::ptrdiff_t q0 = in.faceStride[0], q1 = in.faceStride[1], q2 = in.faceStride[2];
  const double h0 = in.h[0], h1 = in.h[1], h2 = in.h[2];
  const auto larger = [](double a, double b) { return a < b ? b : a; };  // std::max
  for (int i = 0; i < n; ++i) {
    const double l0 = u0[i], l1 = u1[i], l2 = u2[i];
    const double g0 = u0[i + q0], g1 = u1[i + q1], g2 = u2[i + q2];
    double r = 0;
    r += larger(std::fabs(l0), std::fabs(g0)) / h0;
    r += larger(std::fabs(l1), std::fabs(g1)) / h1;
    r += larger(std::fabs(l2), std::fabs(g2)) / h2;
    rate[i] = r;
    speed[i] = larger(larger(std::fabs(l0), std::fabs(l1)), std::fabs(l2));
    // x * 0 is NaN for x = NaN or inf, else 0
    finite[i] = ((l0 * 0.0 + g0 * 0.0) + (l1 * 0.0 + g1 * 0.0)) + (l2 * 0.0 + g2 * 0.0);
  }
  if (in.uPrev[0]) {
    const double* __restrict p0 = in.uPrev[0];
    const double* __restrict p1 = in.uPrev[1];
    const double* __restrict p2 = in.uPrev[2];
    for (int i = 0; i < n; ++i)
      change[i] = larger(larger(std::fabs(u0[i] - p0[i]), std::fabs(u1[i] - p1[i])),
                         std::fabs(u2[i] - p2[i]));
  }
}

/// Cells [i0, i1) of a row without a boundary face across axis a (stride s of p along a): the
/// cell gradient of p along a, the mean of its two face gradients (p_i - p_{i-s}) / h and
/// (p_{i+s} - p_i) / h, each formed with ih = 1 / h.
inline void gradientRow(const double* __restrict p, std::ptrdiff_t s, double ih, int i0, int i1,
                        double* __restrict out) {
  for (int i = i0; i < i1; ++i) out[i] = 0.5 * ((p[i] - p[i - s]) * ih + (p[i + s] - p[i]) * ih);
}

}  // namespace coloc::fv
