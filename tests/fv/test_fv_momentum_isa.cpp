// The explicit momentum terms (fv/src/momentum_kernels.hpp) on every instruction set this CPU
// runs, against the scalar formulation they replace (reference() below, the kernel as it was
// before it was vectorised, with its branches), bit for bit, for the three convection schemes
// and the three components, on random fields with both signs of the mass flux and with ties
// (equal neighbours: da db = 0 and da + db = 0, where the limiter picks u_U).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "momentum.hpp"

using namespace coloc;
using namespace coloc::fv;

namespace {

template <Convection C>
double faceValue(double m, double a, double b, double c, double d) {
  if constexpr (C == Convection::Central) {
    (void)m, (void)a, (void)d;
    return 0.5 * (b + c);
  } else {
    const double up = m >= 0 ? b : c;
    const double dn = m >= 0 ? c : b;
    const double uu = m >= 0 ? a : d;
    const double da = up - uu, db = dn - up;
    if (da * db <= 0.0) return up;
    if constexpr (C == Convection::VanLeer) {
      return up + da * db / (da + db);
    } else {
      return up + 0.5 * (std::fabs(da) < std::fabs(db) ? da : db);
    }
  }
}

// The scalar kernel of fv/src/momentum.cpp before the vectorisation, verbatim.
template <Convection C>
void reference(int d, const FaceField& u, const FaceField& M, const CellField& eps,
               const MomentumParams& prm, const IndexBox& box, Field3<double>& H) {
  const Field3<double>& Ud = u[d];
  const double nu = prm.nu;
  const double hd = prm.h[d];
  const double* ud = Ud.data().data();
  const double* md = M[d].data().data();
  const double* ec = eps.data().data();
  double* hp = H.data().data();
  const std::ptrdiff_t sd = Ud.stride(d);
  const std::ptrdiff_t cd = eps.stride(d);
  int es[2], ne = 0;
  for (int e = 0; e < 3; ++e)
    if (e != d) es[ne++] = e;
  const double* ue[2] = {u[es[0]].data().data(), u[es[1]].data().data()};
  const double* me[2] = {M[es[0]].data().data(), M[es[1]].data().data()};
  std::ptrdiff_t se[2], see[2], sde[2], ce[2];
  double he[2];
  for (int t = 0; t < 2; ++t) {
    const int e = es[t];
    se[t] = Ud.stride(e);
    see[t] = u[e].stride(e);
    sde[t] = u[e].stride(d);
    ce[t] = eps.stride(e);
    he[t] = prm.h[e];
  }
  const double ihd = 1.0 / hd;
  for (int k = box.lo[2]; k < box.hi[2]; ++k)
    for (int j = box.lo[1]; j < box.hi[1]; ++j) {
      const std::ptrdiff_t q0 = Ud.index(box.lo[0], j, k);
      const std::ptrdiff_t c0 = eps.index(box.lo[0], j, k);
      const std::ptrdiff_t h0 = H.index(box.lo[0], j, k);
      const std::ptrdiff_t qe0[2] = {u[es[0]].index(box.lo[0], j, k),
                                     u[es[1]].index(box.lo[0], j, k)};
      const int ni = box.hi[0] - box.lo[0];
      for (int i = 0; i < ni; ++i) {
        const std::ptrdiff_t q = q0 + i, c = c0 + i;
        const double mR = 0.5 * (md[q] + md[q + sd]);
        const double mL = 0.5 * (md[q - sd] + md[q]);
        const double phR = faceValue<C>(mR, ud[q - sd], ud[q], ud[q + sd], ud[q + 2 * sd]);
        const double phL = faceValue<C>(mL, ud[q - 2 * sd], ud[q - sd], ud[q], ud[q + sd]);
        double conv = (mR * phR - mL * phL) * ihd;
        const double tauR = 2.0 * nu * ec[c] * (ud[q + sd] - ud[q]) * ihd;
        const double tauL = 2.0 * nu * ec[c - cd] * (ud[q] - ud[q - sd]) * ihd;
        double visc = (tauR - tauL) * ihd;
        for (int t = 0; t < 2; ++t) {
          const std::ptrdiff_t s = se[t], qe = qe0[t] + i;
          const double* m = me[t];
          const double* w = ue[t];
          const double ihe = 1.0 / he[t];
          const double mLo = 0.5 * (m[qe] + m[qe - sde[t]]);
          const double mHi = 0.5 * (m[qe + see[t]] + m[qe + see[t] - sde[t]]);
          const double pLo = faceValue<C>(mLo, ud[q - 2 * s], ud[q - s], ud[q], ud[q + s]);
          const double pHi = faceValue<C>(mHi, ud[q - s], ud[q], ud[q + s], ud[q + 2 * s]);
          conv += (mHi * pHi - mLo * pLo) * ihe;
          const std::ptrdiff_t cs = ce[t];
          const double eLo = 0.25 * (ec[c] + ec[c - cd] + ec[c - cs] + ec[c - cd - cs]);
          const double eHi = 0.25 * (ec[c + cs] + ec[c + cs - cd] + ec[c] + ec[c - cd]);
          const double tLo =
              nu * eLo * ((ud[q] - ud[q - s]) * ihe + (w[qe] - w[qe - sde[t]]) * ihd);
          const double tHi =
              nu * eHi *
              ((ud[q + s] - ud[q]) * ihe + (w[qe + see[t]] - w[qe + see[t] - sde[t]]) * ihd);
          visc += (tHi - tLo) * ihe;
        }
        hp[h0 + i] = visc - conv;
      }
    }
}

void referenceTerms(int d, const FaceField& u, const FaceField& M, const CellField& eps,
                    const MomentumParams& prm, const IndexBox& box, Field3<double>& H) {
  switch (prm.convection) {
    case Convection::Central:
      return reference<Convection::Central>(d, u, M, eps, prm, box, H);
    case Convection::VanLeer:
      return reference<Convection::VanLeer>(d, u, M, eps, prm, box, H);
    case Convection::Minmod:
      return reference<Convection::Minmod>(d, u, M, eps, prm, box, H);
  }
}

// Random values; one in four is a copy of a neighbour along x, y or z (ties in the limiter).
void fillRandom(Field3<double>& f, std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> val(lo, hi);
  std::uniform_int_distribution<int> pick(0, 7);
  auto data = f.data();
  const std::ptrdiff_t strides[3] = {1, f.strideY(), f.strideZ()};
  for (std::size_t i = 0; i < data.size(); ++i) {
    const int p = pick(rng);
    const auto s = static_cast<std::size_t>(strides[p % 3]);
    data[i] = p < 2 && i >= s ? data[i - s] : val(rng);
  }
}

bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

}  // namespace

TEST(MomentumIsa, EveryVariantMatchesTheScalarKernelBitwise) {
  // 13 faces along x: full packs of 2, 4 and 8 and a remainder on every row.
  const Int3 n{13, 6, 5};
  const int g = 2;
  const FieldLayout cl{n, g, {0, 0, 0}};
  FaceField u, M;
  for (int d = 0; d < 3; ++d) {
    FieldLayout fl = cl;
    fl.stagger[d] = 1;
    u[d] = Field3<double>(fl);
    M[d] = Field3<double>(fl);
  }
  CellField eps(cl);
  std::mt19937_64 rng(20261205);
  for (int d = 0; d < 3; ++d) {
    fillRandom(u[d], rng, -1.0, 1.0);
    fillRandom(M[d], rng, -0.8, 0.8);
  }
  fillRandom(eps, rng, 0.35, 1.0);
  int variants = 0;
  for (auto conv : {Convection::Central, Convection::VanLeer, Convection::Minmod}) {
    MomentumParams prm;
    prm.nu = 1.3e-3;
    prm.h = {0.011, 0.013, 0.017};
    prm.convection = conv;
    for (int d = 0; d < 3; ++d) {
      IndexBox box{{0, 0, 0}, n};
      box.hi[d] += 1;  // the faces of component d, the block's high face included
      Field3<double> want(u[d].layout(), -7.0);
      referenceTerms(d, u, M, eps, prm, box, want);
      for (auto isa :
           {MomentumIsa::Widest, MomentumIsa::Build, MomentumIsa::Avx2, MomentumIsa::Avx512}) {
        Field3<double> got(u[d].layout(), -7.0);
        if (!explicitTermsOn(isa, d, u, M, eps, prm, box, got)) continue;
        ++variants;
        long long differ = 0;
        for (std::size_t i = 0; i < want.data().size(); ++i)
          if (!sameBits(got.data()[i], want.data()[i])) ++differ;
        EXPECT_EQ(differ, 0) << "scheme " << static_cast<int>(conv) << ", component " << d
                             << ", isa " << static_cast<int>(isa);
      }
    }
  }
  EXPECT_GE(variants, 3 * 3 * 2);  // Widest and Build run everywhere
}

TEST(MomentumIsa, MassFluxesAreTheFaceMeans) {
  const Int3 n{11, 4, 3};
  const FieldLayout cl{n, 2, {0, 0, 0}};
  FaceField u, M;
  for (int d = 0; d < 3; ++d) {
    FieldLayout fl = cl;
    fl.stagger[d] = 1;
    u[d] = Field3<double>(fl);
    M[d] = Field3<double>(fl, -7.0);
  }
  CellField eps(cl);
  std::mt19937_64 rng(7);
  for (int d = 0; d < 3; ++d) fillRandom(u[d], rng, -1.0, 1.0);
  fillRandom(eps, rng, 0.35, 1.0);
  massFluxes(u, eps, M);
  for (int d = 0; d < 3; ++d) {
    IndexBox box = u[d].allocated();
    box.lo[d] += 1;
    box.hi[d] -= 1;
    forEach(box, [&](int i, int j, int k) {
      const int im = i - (d == 0), jm = j - (d == 1), km = k - (d == 2);
      const double want = 0.5 * (eps(im, jm, km) + eps(i, j, k)) * u[d](i, j, k);
      ASSERT_TRUE(sameBits(M[d](i, j, k), want)) << d << " " << i << " " << j << " " << k;
    });
  }
}

TEST(MomentumIsa, EveryPredictorVariantMatchesTheScalarLoopBitwise) {
  const Int3 n{13, 6, 5};
  const FieldLayout cl{n, 2, {0, 0, 0}};
  CellField en(cl), eo(cl), K(cl), KUp(cl);
  std::mt19937_64 rng(99);
  fillRandom(en, rng, 0.35, 1.0);
  fillRandom(eo, rng, 0.35, 1.0);
  fillRandom(K, rng, 0.0, 50.0);
  fillRandom(KUp, rng, -5.0, 5.0);
  int variants = 0;
  for (int c = 0; c < 3; ++c) {
    FieldLayout fl = cl;
    fl.stagger[c] = 1;
    Field3<double> u0(fl), Hn(fl), Ho(fl);
    fillRandom(u0, rng, -1.0, 1.0);
    fillRandom(Hn, rng, -10.0, 10.0);
    fillRandom(Ho, rng, -10.0, 10.0);
    PredictFaces p;
    p.c = c;
    p.box = IndexBox{{0, 0, 0}, n};
    p.box.hi[c] += 1;
    p.eps = &en, p.epsOld = &eo, p.K = &K, p.KUp = &KUp, p.Hn = &Hn, p.Ho = &Ho;
    p.ca = 1.25, p.cb = -0.25, p.idt = 1.0 / 3e-4, p.g = c == 2 ? -9.81 : 0.0;
    // The loop of step.cpp's predictVelocity() before it moved to momentum_kernels.hpp.
    Field3<double> wantU = u0, wantP(fl, -7.0);
    {
      const std::ptrdiff_t cs = en.stride(c);
      const double* enp = en.data().data();
      const double* eop = eo.data().data();
      const double* kk = K.data().data();
      const double* kup = KUp.data().data();
      double* up = wantU.data().data();
      double* pp = wantP.data().data();
      const double* hn = Hn.data().data();
      const double* ho = Ho.data().data();
      for (int k = p.box.lo[2]; k < p.box.hi[2]; ++k)
        for (int j = p.box.lo[1]; j < p.box.hi[1]; ++j) {
          const std::ptrdiff_t q0 = wantU.index(p.box.lo[0], j, k),
                               c0 = en.index(p.box.lo[0], j, k), h0 = Hn.index(p.box.lo[0], j, k);
          for (int i = 0; i < p.box.hi[0] - p.box.lo[0]; ++i) {
            const std::ptrdiff_t q = q0 + i, cc = c0 + i, hh = h0 + i;
            const double efn = 0.5 * (enp[cc - cs] + enp[cc]);
            const double efo = 0.5 * (eop[cc - cs] + eop[cc]);
            const double kf = 0.5 * (kk[cc - cs] + kk[cc]);
            const double kupf = 0.5 * (kup[cc - cs] + kup[cc]);
            const double E = p.ca * hn[hh] + p.cb * ho[hh];
            pp[q] = up[q];
            up[q] = (efo * up[q] * p.idt + E + efn * p.g + kupf) / (efn * p.idt + kf);
          }
        }
    }
    for (auto isa :
         {MomentumIsa::Widest, MomentumIsa::Build, MomentumIsa::Avx2, MomentumIsa::Avx512}) {
      Field3<double> U = u0, P(fl, -7.0);
      if (!predictFacesOn(isa, p, U, P)) continue;
      ++variants;
      long long differ = 0;
      for (std::size_t i = 0; i < U.data().size(); ++i)
        differ += !sameBits(U.data()[i], wantU.data()[i]) + !sameBits(P.data()[i], wantP.data()[i]);
      EXPECT_EQ(differ, 0) << "component " << c << ", isa " << static_cast<int>(isa);
    }
  }
  EXPECT_GE(variants, 3 * 2);
}
