#include "momentum.hpp"

#include <cmath>

namespace coloc::fv {

namespace {

inline std::ptrdiff_t strideOf(const Field3<double>& f, int e) {
  return e == 0 ? 1 : e == 1 ? f.strideY() : f.strideZ();
}

/// Value at the face between b and c (a before b, d after c along the axis), for mass flux m.
template <Convection C>
inline double faceValue(double m, double a, double b, double c, double d) {
  if constexpr (C == Convection::Central) {
    (void)m, (void)a, (void)d;
    return 0.5 * (b + c);
  } else {
    const double up = m >= 0 ? b : c;
    const double dn = m >= 0 ? c : b;
    const double uu = m >= 0 ? a : d;
    // With da = u_U - u_UU, db = u_D - u_U and r = da/db: psi(r) db / 2 is
    //   van Leer  da db / (da + db) when da db > 0, else 0
    //   minmod    minmod(da, db) / 2
    const double da = up - uu, db = dn - up;
    if (da * db <= 0.0) return up;
    if constexpr (C == Convection::VanLeer) {
      return up + da * db / (da + db);
    } else {
      return up + 0.5 * (std::fabs(da) < std::fabs(db) ? da : db);
    }
  }
}

template <Convection C>
void kernel(int d, const FaceField& u, const FaceField& M, const CellField& eps,
            const MomentumParams& prm, const IndexBox& box, Field3<double>& H) {
  const Field3<double>& Ud = u[d];
  const double nu = prm.nu;
  const double hd = prm.h[d];
  const double* ud = Ud.data().data();
  const double* md = M[d].data().data();
  const double* ec = eps.data().data();
  double* hp = H.data().data();
  const std::ptrdiff_t sd = strideOf(Ud, d);   // along d in the layout of component d
  const std::ptrdiff_t cd = strideOf(eps, d);  // along d in the cell layout
  // Transverse axes.
  int es[2], ne = 0;
  for (int e = 0; e < 3; ++e)
    if (e != d) es[ne++] = e;
  const double* ue[2] = {u[es[0]].data().data(), u[es[1]].data().data()};
  const double* me[2] = {M[es[0]].data().data(), M[es[1]].data().data()};
  std::ptrdiff_t se[2], see[2], sde[2], ce[2];
  double he[2];
  for (int t = 0; t < 2; ++t) {
    const int e = es[t];
    se[t] = strideOf(Ud, e);     // along e, layout of component d
    see[t] = strideOf(u[e], e);  // along e, layout of component e
    sde[t] = strideOf(u[e], d);  // along d, layout of component e
    ce[t] = strideOf(eps, e);    // along e, cell layout
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
        // Along d: control-volume faces at the centres of cells c (high) and c - e_d (low).
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
          // Edges below (between q - s and q) and above (between q and q + s) along e.
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

}  // namespace

void massFluxes(const FaceField& u, const CellField& eps, FaceField& M) {
  const double* ec = eps.data().data();
  for (int d = 0; d < 3; ++d) {
    const Field3<double>& U = u[d];
    Field3<double>& m = M[d];
    IndexBox box = U.allocated();
    box.lo[d] += 1;  // face idx needs cells idx - e_d and idx
    box.hi[d] -= 1;
    const std::ptrdiff_t cd = strideOf(eps, d);
    const double* up = U.data().data();
    double* mp = m.data().data();
    for (int k = box.lo[2]; k < box.hi[2]; ++k)
      for (int j = box.lo[1]; j < box.hi[1]; ++j) {
        const std::ptrdiff_t q0 = U.index(box.lo[0], j, k);
        const std::ptrdiff_t c0 = eps.index(box.lo[0], j, k);
        for (int i = 0; i < box.hi[0] - box.lo[0]; ++i)
          mp[q0 + i] = 0.5 * (ec[c0 + i - cd] + ec[c0 + i]) * up[q0 + i];
      }
  }
}

void explicitTerms(int d, const FaceField& u, const FaceField& M, const CellField& eps,
                   const MomentumParams& prm, const IndexBox& box, Field3<double>& H) {
  switch (prm.convection) {
    case Convection::Central:
      kernel<Convection::Central>(d, u, M, eps, prm, box, H);
      break;
    case Convection::VanLeer:
      kernel<Convection::VanLeer>(d, u, M, eps, prm, box, H);
      break;
    case Convection::Minmod:
      kernel<Convection::Minmod>(d, u, M, eps, prm, box, H);
      break;
  }
}

}  // namespace coloc::fv
