// The pressure equation's rows away from boundary faces (fv/src/cell_rows.hpp, vectorised by
// the compiler) against the cell-by-cell form they replace in step.cpp (reference*() below, the
// arithmetic of that form for a cell without a boundary face), bit for bit: the right-hand side,
// its scale term, the initial guess and the 7 matrix coefficients, on random fields, rows of
// every length from 1 to 37 cells (vector bodies and remainders) starting at any cell, and the
// "some K_f is not zero" flag on zero, signed-zero, non-zero and NaN coefficients; the rates
// (CFL sum, largest speed and change) and the finiteness flag on NaN and infinite velocities;
// the cell pressure gradient.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "cell_rows.hpp"

using namespace coloc::fv;

namespace {

// A block of nx x ny x nz cells with one ghost layer, x fastest; faces of axis a: one more
// along a (the low face of cell i is face i).
struct Block {
  int nx = 40, ny = 3, nz = 3;
  std::ptrdiff_t sy = nx + 2, sz = (nx + 2) * (ny + 2);
  std::size_t cells = static_cast<std::size_t>((nx + 2) * (ny + 2) * (nz + 2));
  std::ptrdiff_t cell(int i, int j, int k) const { return (i + 1) + (j + 1) * sy + (k + 1) * sz; }
};

std::vector<double> randomField(std::size_t n, std::mt19937& g, double lo, double hi) {
  std::uniform_real_distribution<double> d(lo, hi);
  std::vector<double> v(n);
  for (auto& x : v) x = d(g);
  return v;
}

bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

}  // namespace

TEST(CellRows, RhsMatchesTheCellByCellForm) {
  const Block b;
  std::mt19937 g(7);
  const auto eps = randomField(b.cells, g, 0.35, 1.0);
  const auto epsOld = randomField(b.cells, g, 0.35, 1.0);
  const auto p = randomField(b.cells, g, -3.0, 3.0);
  // face fields on the cell layout (the low face of cell i at its index), strides per axis
  std::vector<double> u[3];
  for (auto& f : u) f = randomField(b.cells, g, -2.0, 2.0);
  const double h[3] = {0.013, 0.021, 0.017}, dt = 3.7e-4, idt = 1.0 / dt;
  const std::ptrdiff_t st[3] = {1, b.sy, b.sz};
  for (int len = 1; len <= 37; ++len)
    for (int i0 : {0, 1, 2, 3}) {
      if (i0 + len > b.nx) continue;
      for (const bool warm : {false, true}) {
        const std::ptrdiff_t c0 = b.cell(0, 1, 1);
        RhsRow row{};
        row.eps = eps.data() + c0;
        row.epsOld = epsOld.data() + c0;
        for (int a = 0; a < 3; ++a) {
          row.u[a] = u[a].data() + c0;
          row.cellStride[a] = st[a];
          row.faceStride[a] = st[a];
          row.h[a] = h[a];
        }
        row.p = warm ? p.data() + c0 : nullptr;
        row.idt = idt;
        row.dt = dt;
        std::vector<double> rhs(b.nx, -1), sc2(b.nx, -1), sol(b.nx, -1);
        rhsRow(row, i0, i0 + len, rhs.data(), sc2.data(), sol.data());
        for (int i = 0; i < b.nx; ++i) {
          if (i < i0 || i >= i0 + len) {  // nothing written outside [i0, i1)
            EXPECT_EQ(rhs[i], -1.0);
            EXPECT_EQ(sol[i], -1.0);
            continue;
          }
          // the cell-by-cell form (step.cpp, a cell without boundary faces)
          const std::ptrdiff_t c = c0 + i;
          double div = 0, flux = 0;
          for (int a = 0; a < 3; ++a) {
            const std::ptrdiff_t s = st[a], q = c, qs = st[a];
            const double elo = 0.5 * (eps[c - s] + eps[c]), ehi = 0.5 * (eps[c] + eps[c + s]);
            div += (ehi * u[a][q + qs] - elo * u[a][q]) / h[a];
            flux += (std::fabs(ehi * u[a][q + qs]) + std::fabs(elo * u[a][q])) / h[a];
          }
          const double de = eps[c] - epsOld[c];
          const double want = -div - de * idt;
          const double sc = flux + std::fabs(de) * idt;
          EXPECT_TRUE(sameBits(rhs[i], want)) << "len " << len << " cell " << i;
          EXPECT_TRUE(sameBits(sc2[i], sc * sc)) << "len " << len << " cell " << i;
          EXPECT_TRUE(sameBits(sol[i], warm ? p[c] * dt : 0.0));
        }
      }
    }
}

TEST(CellRows, MatrixMatchesTheCellByCellForm) {
  const Block b;
  std::mt19937 g(11);
  const auto eps = randomField(b.cells, g, 0.35, 1.0);
  auto K = randomField(b.cells, g, 0.0, 50.0);
  const double h[3] = {0.013, 0.021, 0.017}, dt = 3.7e-4;
  const std::ptrdiff_t st[3] = {1, b.sy, b.sz};
  const std::ptrdiff_t c0 = b.cell(0, 1, 1);
  MatrixRow row{};
  row.eps = eps.data() + c0;
  row.K = K.data() + c0;
  for (int a = 0; a < 3; ++a) {
    row.cellStride[a] = st[a];
    row.h[a] = h[a];
  }
  row.dt = dt;
  std::vector<double> w(6 * static_cast<std::size_t>(b.nx)),
      out(7 * static_cast<std::size_t>(b.nx));
  for (int len = 1; len <= 37; ++len)
    for (int i0 : {0, 1, 2, 3}) {
      if (i0 + len > b.nx) continue;
      std::fill(out.begin(), out.end(), -1.0);
      EXPECT_TRUE(
          matrixRow(row, i0, i0 + len, w.data(), static_cast<std::size_t>(b.nx), out.data()));
      for (int i = 0; i < b.nx; ++i) {
        if (i < i0 || i >= i0 + len) {
          EXPECT_EQ(out[7 * i], -1.0);
          continue;
        }
        const std::ptrdiff_t c = c0 + i;
        double diag = 0, off[6];
        for (int a = 0; a < 3; ++a)
          for (int side = 0; side < 2; ++side) {
            const std::ptrdiff_t nb = c + (side == 0 ? -st[a] : st[a]);
            const double ef = 0.5 * (eps[c] + eps[nb]);
            const double kf = 0.5 * (K[c] + K[nb]);
            const double wf = ef * ef / ((ef + kf * dt) * h[a] * h[a]);
            off[2 * a + side] = -wf;
            diag += wf;
          }
        EXPECT_TRUE(sameBits(out[7 * i], diag)) << "len " << len << " cell " << i;
        for (int f = 0; f < 6; ++f) EXPECT_TRUE(sameBits(out[7 * i + 1 + f], off[f]));
      }
    }
  // the flag: no K_f != 0 on zeros of either sign; one non-zero or NaN coefficient sets it
  std::fill(K.begin(), K.end(), 0.0);
  for (std::size_t c = 0; c < K.size(); c += 2) K[c] = -0.0;
  EXPECT_FALSE(matrixRow(row, 0, b.nx, w.data(), static_cast<std::size_t>(b.nx), out.data()));
  K[static_cast<std::size_t>(c0 + 17 + b.sz)] = 1e-300;  // a neighbour across z of cell 17
  EXPECT_TRUE(matrixRow(row, 0, b.nx, w.data(), static_cast<std::size_t>(b.nx), out.data()));
  K[static_cast<std::size_t>(c0 + 17 + b.sz)] = 0.0;
  K[static_cast<std::size_t>(c0 + 5)] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(matrixRow(row, 0, b.nx, w.data(), static_cast<std::size_t>(b.nx), out.data()));
}

TEST(CellRows, RatesMatchTheCellByCellForm) {
  const Block b;
  std::mt19937 g(13);
  std::vector<double> u[3], prev[3];
  for (int a = 0; a < 3; ++a) {
    u[a] = randomField(b.cells, g, -2.0, 2.0);
    prev[a] = randomField(b.cells, g, -2.0, 2.0);
  }
  const double h[3] = {0.013, 0.021, 0.017};
  const std::ptrdiff_t st[3] = {1, b.sy, b.sz};
  const std::ptrdiff_t c0 = b.cell(0, 1, 1);
  const auto ws = static_cast<std::size_t>(b.nx);
  std::vector<double> out(4 * ws);
  RatesRow row{};
  for (int a = 0; a < 3; ++a) {
    row.u[a] = u[a].data() + c0;
    row.uPrev[a] = prev[a].data() + c0;
    row.faceStride[a] = st[a];
    row.h[a] = h[a];
  }
  for (int len = 1; len <= 37; ++len) {
    ratesRow(row, len, out.data(), ws);
    for (int i = 0; i < len; ++i) {
      const std::ptrdiff_t c = c0 + i;
      double r = 0, speed = 0, change = 0;
      for (int a = 0; a < 3; ++a) {
        const double lo = u[a][c], hi = u[a][c + st[a]];
        r += std::max(std::fabs(lo), std::fabs(hi)) / h[a];
        speed = std::max(speed, std::fabs(lo));
        change = std::max(change, std::fabs(lo - prev[a][c]));
      }
      EXPECT_TRUE(sameBits(out[i], r)) << "len " << len << " cell " << i;
      EXPECT_TRUE(sameBits(out[ws + i], speed));
      EXPECT_TRUE(sameBits(out[2 * ws + i], change));
      EXPECT_EQ(out[3 * ws + i], 0.0);
    }
  }
  // a non-finite velocity on any of a cell's 6 faces marks that cell only
  for (const double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
        -std::numeric_limits<double>::infinity()})
    for (int a = 0; a < 3; ++a)
      for (const bool high : {false, true}) {
        const int cell = 9;
        const std::ptrdiff_t at = c0 + cell + (high ? st[a] : 0);
        const double keep = u[a][at];
        u[a][at] = bad;
        ratesRow(row, b.nx, out.data(), ws);
        for (int i = 0; i < b.nx; ++i) {
          // an x face is shared by the two cells beside it in the row (y and z faces by cells
          // of other rows)
          const bool marked = i == cell || (a == 0 && i == (high ? cell + 1 : cell - 1));
          EXPECT_EQ(out[3 * ws + i] != 0.0, marked) << "axis " << a << " cell " << i;
        }
        u[a][at] = keep;
      }
}

TEST(CellRows, GradientMatchesTheCellByCellForm) {
  const Block b;
  std::mt19937 g(17);
  const auto p = randomField(b.cells, g, -3.0, 3.0);
  const std::ptrdiff_t st[3] = {1, b.sy, b.sz};
  const double h[3] = {0.013, 0.021, 0.017};
  const std::ptrdiff_t c0 = b.cell(0, 1, 1);
  std::vector<double> out(static_cast<std::size_t>(b.nx));
  for (int a = 0; a < 3; ++a)
    for (int i0 : {0, 1}) {
      const double ih = 1.0 / h[a];
      std::fill(out.begin(), out.end(), -1.0);
      gradientRow(p.data() + c0, st[a], ih, i0, b.nx - 1, out.data());
      for (int i = 0; i < b.nx; ++i) {
        if (i < i0 || i >= b.nx - 1) {
          EXPECT_EQ(out[i], -1.0);
          continue;
        }
        // fluid.cpp's face gradients of a cell without a boundary face, and their mean
        const std::ptrdiff_t q = c0 + i;
        const double lo = (p[q] - p[q - st[a]]) * ih, hi = (p[q + st[a]] - p[q]) * ih;
        EXPECT_TRUE(sameBits(out[i], 0.5 * (lo + hi))) << "axis " << a << " cell " << i;
      }
    }
}
