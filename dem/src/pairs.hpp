// dem/src/pairs.hpp — the touching pairs of the force loop in chunks, and the contact law over a
// chunk on the vector units.
//
// The force loop (forces.cpp) runs in three passes per chunk of up to kChunk touching entries:
//   1. gather (scalar, branch-free append): for each Verlet entry in list order, the distance
//      test; a touching entry appends (holder, partner, history slot, coefficients, dx, r^2);
//   2. pairChunk (this file): the contact law of every pair of the chunk, one pair per vector
//      lane (GCC's loop vectoriser; 4 or 8 lanes with AVX2 or AVX-512, whose gathers load the
//      partners' columns; a generic x86-64 build has no gathers and runs this loop scalar); its
//      results (force, n x F_t, rolling torque, updated shear, overlap) go to the chunk;
//   3. scatter (scalar): in the chunk's order, which is the list's order, the results are added
//      to both particles, the shear written back, walls computed: every particle receives the
//      same terms in the same order as the one-pass loop, at any rank count.
// The DEM is compiled with -ffp-contract=off, so a pair's bits do not depend on the lane, the
// vector width or a scalar remainder (add, mul, div and sqrt are exactly rounded everywhere), and
// a portable build (COLOC_DEM_NATIVE=OFF) gives the same bits as a native one.
#pragma once

#include "contact.hpp"

namespace coloc::dem::detail {

/// Touching entries gathered before a vector pass: ~29 KB, within L1 with the partners' data.
inline constexpr int kChunk = 128;

struct PairChunk {
  // gathered (pass 1); wall >= 0: a wall entry (code -1 - wall in the list), computed in pass 3
  alignas(64) int i[kChunk], u[kChunk], slot[kChunk], coef[kChunk], wall[kChunk];
  alignas(64) double dx[3][kChunk], r2[kChunk];
  // the holder's r, m, v and omega (pass 1 on AVX-512 stores them, eight lanes at a time, so
  // that pass 2 reads instead of gathering them; see pairChunk's Holder)
  alignas(64) double hold[8][kChunk];
  // results (pass 2)
  alignas(64) double fp[3][kChunk], nxft[3][kChunk], roll[3][kChunk], shear[3][kChunk],
      delta[kChunk];
  int m = 0;
};

/// One particle as the force loop reads it, packed in one cache line (kept current by the
/// integration, pairs.hpp users: dem.cpp, forces.cpp): the distance test of pass 1 reads x and r
/// of a partner from one line instead of four columns, pass 2 its r, v and m from that line.
struct alignas(64) Body {
  double x[3], r, v[3], m;
};
static_assert(sizeof(Body) == 64);

/// What pass 2 reads besides the chunk.
struct PairInputs {
  const Body* body;        // index = local particle
  const double* w[3];      // angular velocity columns
  const double* hS;        // history pool, 3 per slot
  const PairCoeff* coeff;  // [material_i * nMat + material_j]
  double dt;
};

namespace {  // NOLINT(google-build-namespaces,cert-dcl59-cpp): one copy per instruction set

/// Pass 2 over entries [0, ch.m) of the chunk. Wall entries are computed too, on harmless
/// stand-in values (partner = holder, dx = (1, 0, 0)), and ignored by pass 3. Single: one
/// material (every coef is 0), the coefficients are broadcast instead of gathered. Holder: the
/// holder's values are read from ch.hold (the same values as its line and spin columns).
template <Model M, bool Rolling, bool Single, bool Holder>
inline void pairChunk(const PairInputs& in, bool update, PairChunk& ch) {
  const int m = ch.m;
  // the inputs as locals (loads of the pointers inside the loop would block the vectoriser)
  const Body* B = in.body;
  const double *W0 = in.w[0], *W1 = in.w[1], *W2 = in.w[2];
  const double* hS = in.hS;
  const PairCoeff* coeff = in.coeff;
  const double dt = in.dt;
  // ivdep: the lanes are independent (each writes its own k). Not `omp simd`: it would make the
  // small arrays of the body per-lane memory, which GCC 12 then cannot vectorise.
#pragma GCC ivdep
  for (int k = 0; k < m; ++k) {
    const int i = ch.i[k], u = ch.u[k];
    const Body &bi = B[i], &bu = B[u];
    const double ri = Holder ? ch.hold[0][k] : bi.r, rj = bu.r, mi = Holder ? ch.hold[1][k] : bi.m,
                 mj = bu.m;
    // R* and m* with one division, independent of the distance
    const double rs = ri + rj, msum = mi + mj;
    const double q0 = 1.0 / (rs * msum);
    const double Reff = ri * rj * (msum * q0);
    const double meff = mi * mj * (rs * q0);
    const double r = std::sqrt(ch.r2[k]);
    const double inv = 1.0 / r;
    const double nrm[3] = {ch.dx[0][k] * inv, ch.dx[1][k] * inv, ch.dx[2][k] * inv};
    const double delta = rs - r;
    const double wi[3] = {Holder ? ch.hold[5][k] : W0[i], Holder ? ch.hold[6][k] : W1[i],
                          Holder ? ch.hold[7][k] : W2[i]};
    const double wj[3] = {W0[u], W1[u], W2[u]};
    const double vi[3] = {Holder ? ch.hold[2][k] : bi.v[0], Holder ? ch.hold[3][k] : bi.v[1],
                          Holder ? ch.hold[4][k] : bi.v[2]};
    const double vr[3] = {vi[0] - bu.v[0], vi[1] - bu.v[1], vi[2] - bu.v[2]};
    const double ws[3] = {ri * wi[0] + rj * wj[0], ri * wi[1] + rj * wj[1],
                          ri * wi[2] + rj * wj[2]};
    const double wr[3] = {wi[0] - wj[0], wi[1] - wj[1], wi[2] - wj[2]};
    const auto h = static_cast<std::size_t>(3 * ch.slot[k]);
    double sh[3] = {hS[h], hS[h + 1], hS[h + 2]};
    double Fp[3], c[3], rl[3];
    pairForce<M, Rolling>(coeff[Single ? 0 : ch.coef[k]], dt, update, nrm, delta, Reff, meff, vr,
                          ws, wr, sh, Fp, c, rl);
    for (int d = 0; d < 3; ++d) {
      ch.fp[d][k] = Fp[d];
      ch.nxft[d][k] = c[d];
      ch.shear[d][k] = sh[d];
      if constexpr (Rolling) ch.roll[d][k] = rl[d];
    }
    ch.delta[k] = delta;
  }
}

}  // namespace
}  // namespace coloc::dem::detail
