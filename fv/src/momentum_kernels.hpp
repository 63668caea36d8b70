// fv/src/momentum_kernels.hpp — the explicit momentum terms (explicitTerms()) and the predictor's
// update (predictFaces(), momentum.hpp) compiled once per instruction set, as the coupling's drag
// packs (coupling/src/drag_packs.hpp): momentum.cpp for the build's target (SSE2 in the portable
// x86-64 build), momentum_avx2.cpp with -mavx2, momentum_avx512.cpp with -mavx512f, all without
// FMA contraction and with -fno-trapping-math (fv/CMakeLists.txt), so that every variant does the
// same IEEE operations per face in the same order and the results are bitwise those of the
// scalar code (test_fv_momentum_isa). The row loops are written for the vectoriser: contiguous
// along x, the two transverse directions spelled out (no arrays of pointers), the limiter as
// selections, the fields' arrays restrict. explicitTerms() and predictFaces() call the widest
// variant the CPU runs. Everything here has internal linkage (no inline function of one
// instruction set can stand in for another's at link time).
#pragma once

#include <cmath>
#include <cstddef>

#include "momentum.hpp"

namespace coloc::fv {

using ExplicitTermsFn = void (*)(int d, const FaceField& u, const FaceField& M,
                                 const CellField& eps, const MomentumParams& prm,
                                 const IndexBox& box, Field3<double>& H);
void explicitTermsBuild(int, const FaceField&, const FaceField&, const CellField&,
                        const MomentumParams&, const IndexBox&, Field3<double>&);
void explicitTermsAvx2(int, const FaceField&, const FaceField&, const CellField&,
                       const MomentumParams&, const IndexBox&, Field3<double>&);
void explicitTermsAvx512(int, const FaceField&, const FaceField&, const CellField&,
                         const MomentumParams&, const IndexBox&, Field3<double>&);
using PredictFacesFn = void (*)(const PredictFaces& p, Field3<double>& U, Field3<double>& P);
void predictFacesBuild(const PredictFaces&, Field3<double>&, Field3<double>&);
void predictFacesAvx2(const PredictFaces&, Field3<double>&, Field3<double>&);
void predictFacesAvx512(const PredictFaces&, Field3<double>&, Field3<double>&);

namespace {  // NOLINT(google-build-namespaces,cert-dcl59-cpp): one copy per ISA

/// Value at the face between b and c (a before b, d after c along the axis), for mass flux m.
/// Without branches (selections the vectoriser turns into masks); the same values as
///   up, dn, uu = m >= 0 ? (b, c, a) : (c, b, d);  da = up - uu, db = dn - up
///   da db <= 0 ? up : up + psi(r) db / 2
/// with psi(r) db / 2 = da db / (da + db) (van Leer) or minmod(da, db) / 2 (minmod). The limited
/// increment is computed on every lane and discarded where da db <= 0 (a division by zero
/// there only makes a value that is not selected; coloc runs without floating-point traps).
template <Convection C>
inline double faceValue(double m, double a, double b, double c, double d) {
  if constexpr (C == Convection::Central) {
    (void)m, (void)a, (void)d;
    return 0.5 * (b + c);
  } else {
    const bool pos = m >= 0;
    const double up = pos ? b : c;
    const double dn = pos ? c : b;
    const double uu = pos ? a : d;
    const double da = up - uu, db = dn - up;
    double inc;
    if constexpr (C == Convection::VanLeer) {
      inc = da * db / (da + db);
    } else {
      inc = 0.5 * (std::fabs(da) < std::fabs(db) ? da : db);
    }
    const double lim = up + inc;
    return da * db <= 0.0 ? up : lim;
  }
}

/// One transverse axis e of component d: strides and the arrays of component e.
struct Across {
  const double* m;     // M_e
  const double* w;     // u_e
  std::ptrdiff_t s;    // along e, layout of component d
  std::ptrdiff_t see;  // along e, layout of component e
  std::ptrdiff_t sde;  // along d, layout of component e
  std::ptrdiff_t cs;   // along e, cell layout
  double ihe;          // 1 / h_e
};

/// The convective and viscous contributions across e of face q (cell c, face qe of component e),
/// added to conv and visc in the order of the scalar formulation.
template <Convection C>
inline void across(const Across& T, const double* ud, const double* ec, std::ptrdiff_t q,
                   std::ptrdiff_t c, std::ptrdiff_t qe, std::ptrdiff_t cd, double nu, double ihd,
                   double& conv, double& visc) {
  const std::ptrdiff_t s = T.s;
  // Edges below (between q - s and q) and above (between q and q + s) along e.
  const double mLo = 0.5 * (T.m[qe] + T.m[qe - T.sde]);
  const double mHi = 0.5 * (T.m[qe + T.see] + T.m[qe + T.see - T.sde]);
  const double pLo = faceValue<C>(mLo, ud[q - 2 * s], ud[q - s], ud[q], ud[q + s]);
  const double pHi = faceValue<C>(mHi, ud[q - s], ud[q], ud[q + s], ud[q + 2 * s]);
  conv += (mHi * pHi - mLo * pLo) * T.ihe;
  const std::ptrdiff_t cs = T.cs;
  const double eLo = 0.25 * (ec[c] + ec[c - cd] + ec[c - cs] + ec[c - cd - cs]);
  const double eHi = 0.25 * (ec[c + cs] + ec[c + cs - cd] + ec[c] + ec[c - cd]);
  const double tLo = nu * eLo * ((ud[q] - ud[q - s]) * T.ihe + (T.w[qe] - T.w[qe - T.sde]) * ihd);
  const double tHi =
      nu * eHi * ((ud[q + s] - ud[q]) * T.ihe + (T.w[qe + T.see] - T.w[qe + T.see - T.sde]) * ihd);
  visc += (tHi - tLo) * T.ihe;
}

/// H on one row of n faces: hp[i] for face q0 + i (cell c0 + i, faces qa0 + i and qb0 + i of the
/// two transverse components). The arrays of the fields are distinct from H's (restrict).
template <Convection C>
inline void row(int n, double* __restrict hp, const double* __restrict ud,
                const double* __restrict md, const double* __restrict ec, std::ptrdiff_t q0,
                std::ptrdiff_t c0, std::ptrdiff_t qa0, std::ptrdiff_t qb0, std::ptrdiff_t sd,
                std::ptrdiff_t cd, double nu, double ihd, Across A, Across B) {
#pragma GCC ivdep
  for (int i = 0; i < n; ++i) {
    const std::ptrdiff_t q = q0 + i, c = c0 + i;
    // Along d: control-volume faces at the centres of cells c (high) and c - e_d (low).
    const double mR = 0.5 * (md[q] + md[q + sd]);
    const double mL = 0.5 * (md[q - sd] + md[q]);
    const double phR = faceValue<C>(mR, ud[q - sd], ud[q], ud[q + sd], ud[q + 2 * sd]);
    const double phL = faceValue<C>(mL, ud[q - 2 * sd], ud[q - sd], ud[q], ud[q + sd]);
    double conv = (mR * phR - mL * phL) * ihd;
    const double tauR = 2.0 * nu * ec[c] * (ud[q + sd] - ud[q]) * ihd;
    const double tauL = 2.0 * nu * ec[c - cd] * (ud[q] - ud[q - sd]) * ihd;
    double visc = (tauR - tauL) * ihd;
    across<C>(A, ud, ec, q, c, qa0 + i, cd, nu, ihd, conv, visc);
    across<C>(B, ud, ec, q, c, qb0 + i, cd, nu, ihd, conv, visc);
    hp[i] = visc - conv;
  }
}

template <Convection C>
void kernel(int d, const FaceField& u, const FaceField& M, const CellField& eps,
            const MomentumParams& prm, const IndexBox& box, Field3<double>& H) {
  const Field3<double>& Ud = u[d];
  const double nu = prm.nu;
  const double* ud = Ud.data().data();
  const double* md = M[d].data().data();
  const double* ec = eps.data().data();
  double* hp = H.data().data();
  const std::ptrdiff_t sd = Ud.stride(d);              // along d in the layout of component d
  const std::ptrdiff_t cd = eps.stride(d);             // along d in the cell layout
  const int ea = d == 0 ? 1 : 0, eb = d == 2 ? 1 : 2;  // the transverse axes, ascending
  const auto acrossOf = [&](int e) {
    return Across{M[e].data().data(), u[e].data().data(), Ud.stride(e),  u[e].stride(e),
                  u[e].stride(d),     eps.stride(e),      1.0 / prm.h[e]};
  };
  const Across A = acrossOf(ea), B = acrossOf(eb);
  const double ihd = 1.0 / prm.h[d];
  const int ni = box.hi[0] - box.lo[0];
  for (int k = box.lo[2]; k < box.hi[2]; ++k)
    for (int j = box.lo[1]; j < box.hi[1]; ++j)
      row<C>(ni, hp + H.index(box.lo[0], j, k), ud, md, ec, Ud.index(box.lo[0], j, k),
             eps.index(box.lo[0], j, k), u[ea].index(box.lo[0], j, k), u[eb].index(box.lo[0], j, k),
             sd, cd, nu, ihd, A, B);
}

/// The predictor on one row of n faces (predictFaces(), momentum.hpp).
inline void predictRow(int n, double* __restrict up, double* __restrict pp,
                       const double* __restrict en, const double* __restrict eo,
                       const double* __restrict kk, const double* __restrict kup,
                       const double* __restrict hn, const double* __restrict ho, std::ptrdiff_t q0,
                       std::ptrdiff_t c0, std::ptrdiff_t h0, std::ptrdiff_t cs, double ca,
                       double cb, double idt, double gc) {
#pragma GCC ivdep
  for (int i = 0; i < n; ++i) {
    const std::ptrdiff_t q = q0 + i, cc = c0 + i, hh = h0 + i;
    const double efn = 0.5 * (en[cc - cs] + en[cc]);
    const double efo = 0.5 * (eo[cc - cs] + eo[cc]);
    const double kf = 0.5 * (kk[cc - cs] + kk[cc]);
    const double kupf = 0.5 * (kup[cc - cs] + kup[cc]);
    const double E = ca * hn[hh] + cb * ho[hh];
    pp[q] = up[q];
    up[q] = (efo * up[q] * idt + E + efn * gc + kupf) / (efn * idt + kf);
  }
}

inline void predict(const PredictFaces& p, Field3<double>& U, Field3<double>& P) {
  const IndexBox& box = p.box;
  const CellField& eps = *p.eps;
  const std::ptrdiff_t cs = eps.stride(p.c);
  const int ni = box.hi[0] - box.lo[0];
  for (int k = box.lo[2]; k < box.hi[2]; ++k)
    for (int j = box.lo[1]; j < box.hi[1]; ++j)
      predictRow(ni, U.data().data(), P.data().data(), eps.data().data(), p.epsOld->data().data(),
                 p.K->data().data(), p.KUp->data().data(), p.Hn->data().data(), p.Ho->data().data(),
                 U.index(box.lo[0], j, k), eps.index(box.lo[0], j, k), p.Hn->index(box.lo[0], j, k),
                 cs, p.ca, p.cb, p.idt, p.g);
}

}  // namespace

// The functions `terms` and `pred` for one instruction set: explicitTerms() for the scheme
// prm.convection, and predictFaces().
#define COLOC_MOMENTUM_DEFINE(terms, pred)                                        \
  void pred(const PredictFaces& p, Field3<double>& U, Field3<double>& P) {        \
    predict(p, U, P);                                                             \
  }                                                                               \
  void terms(int d, const FaceField& u, const FaceField& M, const CellField& eps, \
             const MomentumParams& prm, const IndexBox& box, Field3<double>& H) { \
    switch (prm.convection) {                                                     \
      case Convection::Central:                                                   \
        kernel<Convection::Central>(d, u, M, eps, prm, box, H);                   \
        break;                                                                    \
      case Convection::VanLeer:                                                   \
        kernel<Convection::VanLeer>(d, u, M, eps, prm, box, H);                   \
        break;                                                                    \
      case Convection::Minmod:                                                    \
        kernel<Convection::Minmod>(d, u, M, eps, prm, box, H);                    \
        break;                                                                    \
    }                                                                             \
  }

}  // namespace coloc::fv
